"""A user's value echoed in an error message, at a bounded length.

Error messages name the offending value and what would be valid; a value from a hostile
file (a YAML alias bomb, a megabyte string) must not turn one message into megabytes.
:func:`shown` is the repr of the value cut at ECHO_LIMIT characters, with the full length
said.
"""
from typing import Any

# characters of a value shown in a message: two lines of a terminal, enough to recognise
# any number, name or short list a user typed.
ECHO_LIMIT = 200


def shown_text(text: str, limit: int = ECHO_LIMIT) -> str:
    """``text``, or its first ``limit`` characters and '... (N characters)' when longer."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text)} characters)"


def shown(value: Any, limit: int = ECHO_LIMIT) -> str:
    """repr(value), cut as :func:`shown_text` cuts (use in place of ``{value!r}``)."""
    return shown_text(repr(value), limit)
