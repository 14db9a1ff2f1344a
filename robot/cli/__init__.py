"""The command-line program ``clearance`` (:mod:`robot.cli.main`; subcommands in :mod:`robot.cli.registry`)."""
