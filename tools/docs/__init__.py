"""Generators of the docs pages written from the code and from measurements, never by
hand (docs/reference/cli.md, docs/results.md), and the browser check of the pages."""
