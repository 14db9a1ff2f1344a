"""The command-line program ``clearance`` (:mod:`robot.cli.main`; subcommands in :mod:`robot.cli.registry`).

``exit_on_error`` and ``progress_bar`` (of the former ``robot.cli`` module) are
re-exported from :mod:`robot.cli.common`, lazily.
"""

from clearance_contact.lazy import lazy_exports

_PUBLIC = {"exit_on_error": "robot.cli.common", "progress_bar": "robot.cli.common"}

__getattr__, __dir__ = lazy_exports(__name__, globals(), _PUBLIC)
