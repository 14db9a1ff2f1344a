"""``python -m robot.cli``: the ``clearance`` program."""

from robot.cli.main import console_main

console_main()
