"""silbridge.mavlink"""
