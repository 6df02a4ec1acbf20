"""The export's encoders (issue 47): each target's contract on exact examples, and the one
mangling of names into C identifiers."""

from __future__ import annotations

import pytest

from flexmech.service.export.encoders import (
    TEXT_LIMIT,
    c_comment,
    c_identifier,
    c_macro,
    c_string,
    hash_comment,
    python_docstring,
)

TRIGRAPHS = "??= ??( ??) ??< ??> ??! ??' ??- ??/"


@pytest.mark.parametrize(
    ("name", "identifier"),
    [
        ("actuation/force/y", "actuation_force_y"),  # as the gripper's input has always been named
        ("end_effector.x", "end_effector_x"),
        ("End Effector..X", "end_effector_x"),
        ("__a__b__", "a_b"),  # no double, leading or trailing underscore (CasADi refuses them)
        ("1st", "x_1st"),
        ("grïpper", "gr_pper"),
        ("夹持器", "x"),
        ("*/\r#include", "include"),
        ("int", "int"),
    ],
)
def test_names_become_c_identifiers_by_one_rule(name, identifier):
    assert c_identifier(name) == identifier


def test_a_macro_joins_identifiers_in_upper_case_and_takes_nothing_else():
    assert c_macro("gripper", "in", "actuation_force_y") == "GRIPPER_IN_ACTUATION_FORCE_Y"
    with pytest.raises(ValueError):
        c_macro("gripper", "in", "a*/b")


@pytest.mark.parametrize(
    ("text", "shown"),
    [
        ("end_effector.x [mm]", "end_effector.x [mm]"),
        ("a*/b", "a* /b"),
        ("/*x*/", "/ *x* /"),
        ("/*/", "/ * /"),
        ("e??(", "e? ?("),
        ("???", "? ? ?"),
        ("a\\", "aU+005C"),
        ("a\rb\nc\x00d\x1b[2J", "a b c d [2J"),
        ("grïpper ☃\u202e", "grU+00EFpper U+2603U+202E"),
        ("\U0001f600", "U+1F600"),
        ('"%n" #x $(shell ls) `ls`', '"%n" #x $(shell ls) `ls`'),
    ],
)
def test_a_c_comment_holds_no_end_no_opening_no_trigraph_and_no_splice(text, shown):
    assert c_comment(text) == shown


def test_every_trigraph_is_broken_in_a_comment():
    assert c_comment(TRIGRAPHS) == "? ?= ? ?( ? ?) ? ?< ? ?> ? ?! ? ?' ? ?- ? ?/"


def test_a_long_title_is_cut_with_a_marker():
    title = "*/" * 50_000
    shown = c_comment(title)
    assert shown == " ".join(["* /"] * (TEXT_LIMIT // 2)) + " [cut: 100000 characters in all]"
    assert c_comment("x" * TEXT_LIMIT) == "x" * TEXT_LIMIT  # at the limit: nothing cut


@pytest.mark.parametrize(
    ("text", "literal"),
    [
        ("end_effector.x [mm]", '"end_effector.x [mm]"'),
        ("e%s%n", '"e%s%n"'),  # data: printf only ever gets it as the argument of a "%s"
        ("e??(", '"e\\?\\?("'),
        ('a"b\\c', '"a\\"b\\\\c"'),
        ("a\rb\n\x00\x1b\x9b", '"a b    "'),
        ("ï1", '"\\303\\2571"'),  # 3-digit octal: the digit after it stays a digit
        ("☃", '"\\342\\230\\203"'),
    ],
)
def test_a_c_string_escapes_everything_outside_printable_ascii(text, literal):
    assert c_string(text) == literal


def test_makefile_and_cmake_comments_are_one_line_without_a_backslash():
    assert hash_comment("a\\\n$(shell touch x)\r`ls`ü") == "aU+005C $(shell touch x) `ls`U+00FC"


def test_a_docstring_text_has_no_quote_and_no_backslash():
    assert python_docstring('"""\rimport os\\') == "U+0022U+0022U+0022 import osU+005C"
