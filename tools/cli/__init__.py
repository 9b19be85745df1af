"""The `silbridge` command line: one module per subcommand; nothing but the command line and tests imports this package."""
