"""One thin module per subcommand: options, progress bars and printing; no computation."""
