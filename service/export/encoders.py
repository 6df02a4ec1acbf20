"""How a document's strings reach the export's generated files: one encoder per place.

A document is untrusted input (someone else may have written it): its name (the title), the
names of its loads, outputs, bodies and contact pairs, and the units and pointers made of them
reach the C sources, the header, the build files and the loader. Every template value made of
such a string goes through exactly one function here (service.export.sources), chosen by where
the value lands:

    c_identifier      part of a C identifier, a macro name or a file name (the one mangling)
    c_macro           a macro name made of identifiers
    c_comment         text inside /* ... */
    c_string          a C string literal, whole: the only way a name reaches printf (as a %s argument)
    hash_comment      text of a Makefile or CMake `#` comment
    python_docstring  text inside a Python docstring

Each result is printable ASCII and holds no syntax of its target, so a string stays data. What a
target cannot hold is shown rather than dropped: a control character (U+0000-U+001F,
U+007F-U+009F: line ends, NUL, escape) as a space, any other character outside printable ASCII
(and the few printable ones a target gives a meaning) as U+XXXX, its code point. Text for a
comment or docstring is cut after `limit` characters, with a marker saying how long it was.
"""

from __future__ import annotations

import re
import unicodedata

TEXT_LIMIT = 200  # characters of a document string shown in a comment or docstring
_NOT_ALPHANUMERIC = re.compile(r"[^0-9a-zA-Z]+")
_IDENTIFIER = re.compile(r"^[a-z][a-z0-9]*(?:_[a-z0-9]+)*$")


def c_identifier(name: str) -> str:
    """The C name of a document's name or pointer, lower case: each run of characters other than
    ASCII letters and digits becomes one underscore, underscores at either end go, a name that
    starts with a digit gets "x_" in front and one with no letter or digit at all is "x".

    The result matches [a-z][a-z0-9]*(_[a-z0-9]+)*: a C identifier (and a part of one), a file
    name and a CasADi function name (no double or trailing underscore). It is no C keyword only
    as a part: the export never uses it alone. The rule is not injective ("a.b", "A_b" and
    "a b" all become a_b): service.export.plan refuses two names of one namespace that meet."""
    out = _NOT_ALPHANUMERIC.sub("_", name).strip("_").lower()
    if not out:
        return "x"
    return f"x_{out}" if out[0].isdigit() else out


def c_macro(*identifiers: str) -> str:
    """The macro name of c_identifier results joined by underscores, upper case:
    c_macro("gripper", "in", "actuation_force_y") == "GRIPPER_IN_ACTUATION_FORCE_Y"."""
    for part in identifiers:
        if not _IDENTIFIER.match(part):
            raise ValueError(f"not a c_identifier: {part!r}")  # a caller's mistake, never a document's
    return "_".join(identifiers).upper()


def c_comment(text: str, limit: int | None = TEXT_LIMIT) -> str:
    """Text for the inside of a C block comment. Printable ASCII stays, except the backslash
    (U+005C); control characters become spaces and other characters U+XXXX. A space is put
    between '*' and '/', '/' and '*', '?' and '?' wherever they would meet. So the text never
    holds "*/" (which would end the comment), "/*" (-Wcomment), "??" (a trigraph under -std=c99,
    -Wtrigraphs), a backslash (a line splice) or a line end: c_comment("a*/b\\r#x??(") ==
    "a* /b #x? ?("."""
    return _shown(text, limit, escaped="\\", apart=("*/", "/*", "??"))


def c_string(text: str) -> str:
    """A whole C string literal, quotes included, of text that a generated program prints.
    Printable ASCII stays, except '"', '\\' and '?', escaped as \\", \\\\ and \\? (so no trigraph
    forms); a control character becomes a space (printed to a terminal it would be a command);
    every other character is kept as its UTF-8 bytes, each a 3-digit octal escape (a digit after
    it cannot extend it, as it would a hex escape). c_string('e??(%n') == '"e\\?\\?(%n"': a
    name reaches printf only as the argument of a "%s" in a format the template fixes."""
    out = []
    for ch in text:
        if unicodedata.category(ch) == "Cc":
            out.append(" ")
        elif ch in '"\\?':
            out.append("\\" + ch)
        elif " " <= ch <= "~":
            out.append(ch)
        else:
            out.extend(f"\\{byte:03o}" for byte in ch.encode("utf-8"))
    return '"' + "".join(out) + '"'


def hash_comment(text: str, limit: int | None = TEXT_LIMIT) -> str:
    """Text for a `#` line comment of a Makefile or a CMakeLists.txt: one line of printable
    ASCII without a backslash (U+005C; make continues a comment line that ends in one); control
    characters become spaces and other characters U+XXXX. Neither tool expands anything in a
    comment, so "$(shell ...)" stays text."""
    return _shown(text, limit, escaped="\\", apart=())


def python_docstring(text: str, limit: int | None = TEXT_LIMIT) -> str:
    """Text for the inside of a Python docstring: printable ASCII without a backslash or a
    double quote (U+005C, U+0022; the one would start an escape, the other could end the
    string); control characters become spaces and other characters U+XXXX."""
    return _shown(text, limit, escaped='\\"', apart=())


def _shown(text: str, limit: int | None, escaped: str, apart: tuple[str, ...]) -> str:
    """Printable ASCII but `escaped` as it is, control characters as spaces, the rest as U+XXXX;
    a space between two characters that would form one of `apart`; cut after `limit` characters."""
    cut = text if limit is None or len(text) <= limit else text[:limit]
    out: list[str] = []
    for ch in cut:
        if unicodedata.category(ch) == "Cc":
            piece = " "
        elif " " <= ch <= "~" and ch not in escaped:
            piece = ch
        else:
            piece = f"U+{ord(ch):04X}"
        if out and out[-1][-1] + piece[0] in apart:
            out.append(" ")
        out.append(piece)
    if len(cut) < len(text):
        out.append(f" [cut: {len(text)} characters in all]")
    return "".join(out)
