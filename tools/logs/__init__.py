"""Run logs: the MCAP writer and schemas, the reader, the integrity check, the viewable Foxglove channels and live view, synthetic logs, the logging benchmarks."""
