"""silbridge.bridge"""
