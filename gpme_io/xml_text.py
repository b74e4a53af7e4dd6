"""Text that goes into an XML file the project writes (URDF, MJCF, JUnit, HTML reports).

ElementTree escapes &, <, > and quotes in attributes and text, so any name is written as
well-formed XML, with two exceptions this module covers:

* characters XML 1.0 cannot hold at all, escaped or not (controls U+0000-U+0008, U+000B,
  U+000C, U+000E-U+001F, lone surrogates, U+FFFE, U+FFFF).  A file that must give a name
  back exactly (URDF, MJCF) refuses such a name (:func:`xml_char_problem`); a report shows
  it as its Python escape, ``\\x01`` (:func:`xml_safe_text`, :func:`make_tree_safe`);
* comments, which have no escapes: "--" may not appear in one and it may not end with "-"
  (:func:`xml_comment`).
"""
import re
import xml.etree.ElementTree as ET
from typing import Optional

# every character that is not an XML 1.0 Char (https://www.w3.org/TR/xml/#charsets)
NOT_XML_CHAR = re.compile("[^\t\n\r\u0020-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def xml_char_problem(label: str, value: str) -> Optional[str]:
    """The problem of ``value`` (a str) holding characters XML 1.0 cannot hold, naming
    ``label``, the value and the characters; None when it has none."""
    bad = sorted(set(NOT_XML_CHAR.findall(value)))
    if not bad:
        return None
    codes = ", ".join(f"U+{ord(c):04X}" for c in bad)
    return f"{label} {value!r}: character {codes} cannot be written in XML 1.0"


def xml_safe_text(text: str) -> str:
    """``text`` with each character XML 1.0 cannot hold replaced by its Python escape
    (``"a\\x01b"`` -> ``"a\\\\x01b"``); other text unchanged."""
    return NOT_XML_CHAR.sub(lambda m: repr(m.group())[1:-1], text)


def comment_text(text: str) -> str:
    """``text`` made valid as the content of an XML comment: non-XML characters escaped
    (:func:`xml_safe_text`), "--" written "- -" and a space after a final "-"."""
    text = re.sub("-(?=-)", "- ", xml_safe_text(str(text)))
    return text + " " if text.endswith("-") else text


def xml_comment(text: str) -> ET.Element:
    """An ElementTree comment ``<!-- text -->`` (one space each side) valid for any text."""
    return ET.Comment(comment_text(f" {text} "))


def make_tree_safe(root: ET.Element) -> ET.Element:
    """Escape (:func:`xml_safe_text`) every text, tail, attribute name and value and
    comment under ``root``, in place; returns ``root``.  For documents built from data
    (reports), where showing a control character as ``\\x01`` is better than refusing."""
    for el in root.iter():
        if el.tag is ET.Comment:
            el.text = comment_text(el.text or "")
        elif el.text is not None:
            el.text = xml_safe_text(el.text)
        if el.tail is not None:
            el.tail = xml_safe_text(el.tail)
        if any(NOT_XML_CHAR.search(f"{k}{v}") for k, v in el.attrib.items()):
            safe = {xml_safe_text(str(k)): xml_safe_text(str(v)) for k, v in el.attrib.items()}
            el.attrib.clear()
            el.attrib.update(safe)
    return root
