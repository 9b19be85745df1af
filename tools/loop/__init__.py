"""The flight loop as a library: options, wiring of bridge, FC and transports, the run log sink, stopping on a signal, the loop under CPU load."""
