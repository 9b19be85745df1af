"""silbridge.shm"""
