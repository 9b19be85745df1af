"""`silbridge soak`: a long real-time run with a ground station attached, checked for growth."""
