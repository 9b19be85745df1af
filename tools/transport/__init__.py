"""The transport comparison (Table 2): shared memory against MAVLink HIL."""
