"""The one logging setup of the command line.

Every library module reports what it is doing through a logger under "gpme"
(``logging.getLogger("gpme.verify")``, "gpme.crosscheck.pinocchio", "gpme.integrate", ...)
and never prints: as a library (tests, notebooks, a user's script) it is silent unless the
caller configures logging.  The `gpme` command configures it once, here: records of INFO
and above under "gpme" go to standard output as their message alone (the lines the
commands have always printed), warnings prefixed "WARNING", Python warnings too.

Kept as direct prints, on purpose: a command's own result lines and its "error:" line
(gpme/cli.py, gpme_study/command.py, the generators' ``__main__``: the command's output,
not a log), and the terminal writers of gpme_io (progress.py's bar and log lines on stderr,
budget.py's estimate lines): they draw on a terminal, which is their job.
"""
import logging
import sys
import warnings

ROOT_LOGGER = "gpme"


class _CurrentStdout(logging.StreamHandler):
    """Writes to whatever ``sys.stdout`` is when a record is emitted (a redirected or
    captured stream, pytest's capsys), not to the stream of the moment it was made."""

    def __init__(self):
        super().__init__(sys.stdout)

    @property
    def stream(self):
        return sys.stdout

    @stream.setter
    def stream(self, value):       # StreamHandler.__init__ sets it; the property wins
        pass


class _MessageFormatter(logging.Formatter):
    def format(self, record):
        text = record.getMessage()
        return f"WARNING {text}" if record.levelno >= logging.WARNING else text


def _warning_line(message, category, filename, lineno, file=None, line=None):
    """warnings.showwarning for the command: a Python warning (an accepted non-physical
    inertia, a suspicious beam section, a library's deprecation) as one 'WARNING <message>'
    line, not the file, line and source of the warnings module's default."""
    logging.getLogger(f"{ROOT_LOGGER}.warnings").warning(f"{message} ({category.__name__})")


def configure(level: int = logging.INFO) -> logging.Logger:
    """Show the "gpme" loggers' records of ``level`` and above on standard output, once
    per process (a second call only sets the level), and Python warnings as such lines;
    returns the "gpme" logger."""
    warnings.showwarning = _warning_line
    logger = logging.getLogger(ROOT_LOGGER)
    if not any(isinstance(h, _CurrentStdout) for h in logger.handlers):
        handler = _CurrentStdout()
        handler.setFormatter(_MessageFormatter())
        logger.addHandler(handler)
    logger.setLevel(level)
    logger.propagate = False       # shown once, not again by a root handler
    return logger
