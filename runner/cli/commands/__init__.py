"""One module per `scenario` sub-command, discovered by :mod:`runner.cli.main`.

A command module defines ``NAME``, ``HELP``, ``configure(parser)`` (add its arguments) and
``execute(args, out, err) -> int`` (an exit code). Keep imports at module level light: heavy ones go inside
``execute`` so that ``scenario --help`` stays fast.
"""
