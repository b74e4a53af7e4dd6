"""The one logging setup (gpme/console_log.py): the library logs under "gpme" and prints
nothing; the command shows INFO and above on standard output, as plain lines."""
import logging

import pytest

from gpme import console_log


@pytest.fixture
def clean_gpme_logger():
    logger = logging.getLogger(console_log.ROOT_LOGGER)
    saved = (list(logger.handlers), logger.level, logger.propagate)
    logger.handlers.clear()
    yield logger
    logger.handlers[:], logger.level, logger.propagate = saved[0], saved[1], saved[2]


def test_the_library_is_silent_until_the_command_configures_it(clean_gpme_logger, capsys):
    engine_log = logging.getLogger("gpme.crosscheck.pinocchio")
    engine_log.info("crane_rigid: 40 states")
    assert capsys.readouterr().out == ""
    console_log.configure()
    console_log.configure()                     # once: a second call adds no handler
    engine_log.info("crane_rigid: 40 states")
    logging.getLogger("gpme.verify").warning("a run ended inside its transient")
    logging.getLogger("gpme.sweep").debug("not shown at INFO")
    assert capsys.readouterr().out == ("crane_rigid: 40 states\n"
                                       "WARNING a run ended inside its transient\n")


def test_the_command_shows_an_engine_steps_lines(tmp_path, capsys):
    """`gpme verify --only pinocchio` prints the Pinocchio step's own lines (its logger's
    records were dropped before the setup: never shown)."""
    from gpme import cli
    code = cli.main(["verify", "--quick", "--no-progress", "--only", "pinocchio",
                     "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "[pinocchio] ..." in out
    assert any(line.startswith("crane_rigid") and " states, " in line and "failing" in line
               for line in out.splitlines()), out
