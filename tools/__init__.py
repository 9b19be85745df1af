"""silbridge.tools"""
