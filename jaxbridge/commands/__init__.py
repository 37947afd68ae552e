"""What the command-line tools do once their flags are parsed: train.py -> `commands.train`, eval.py ->
`commands.evaluate`. Bad input raises `jaxbridge.utils.cli.UsageError` (one line, exit 2)."""
