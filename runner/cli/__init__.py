"""The ``scenario`` command: argument parsing, rendering for the terminal, one module per sub-command."""
