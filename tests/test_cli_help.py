"""The command line explains itself: a description on every subcommand's help page, a help
text on every option, and ``--version``."""

import argparse

import pytest

import comgrasp_pin as cg
from comgrasp_pin.cli import build_parser, main


def _subcommands():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices


@pytest.mark.parametrize("name", sorted(_subcommands()))
def test_every_subcommand_has_a_description_and_every_option_a_help(name):
    p = _subcommands()[name]
    assert p.description and len(p.description) > 20, name
    missing = [a.option_strings for a in p._actions if a.option_strings and not a.help]
    assert not missing, f"{name}: options without help: {missing}"


def test_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"comgrasp {cg.__version__}"
