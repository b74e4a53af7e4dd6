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


# how alike a name must be to a valid one to be suggested (difflib's ratio): 0.6 finds one
# or two typed letters wrong in names of 5 or more; case-only differences are always found
SUGGEST_CUTOFF = 0.6


def closest(name: Any, choices, n: int = 1, cutoff: float = SUGGEST_CUTOFF) -> list:
    """Up to ``n`` names of ``choices`` close to ``name`` (difflib, best first); when none
    is, those equal to it but for case.  The one "did you mean" of every message of the
    package (model files, side files, sweep files, expressions)."""
    import difflib
    text, names = str(name), [str(c) for c in choices]
    close = difflib.get_close_matches(text, names, n=n, cutoff=cutoff)
    if close:
        return close
    lower = {c.lower(): c for c in names}
    return [lower[m] for m in difflib.get_close_matches(text.lower(), list(lower), n=n,
                                                        cutoff=cutoff)]


def did_you_mean(name: Any, choices, n: int = 1, cutoff: float = SUGGEST_CUTOFF) -> str:
    """' (did you mean 'x'?)' (several comma-separated when n > 1) or ''."""
    close = closest(name, choices, n, cutoff)
    return f" (did you mean {', '.join(shown(c) for c in close)}?)" if close else ""
