"""A setup's progress (issue 47): each stage said as it starts, and bars over its long inner work
(the Lanczos' modes and the responses to the contact's directions), drawn by the command line on
a terminal, never by the library on its own nor into a JSON reader's output."""
from pathlib import Path

import pytest

import transient
from transient import progress
from transient.case.loading import load
from transient.cli import commands

from small_cases import PAD_DISC

PAD = str(Path(__file__).resolve().parent.parent / "cases" / "pad_disc.toml")
FRICTION = PAD_DISC + ["contact.pad_disc.friction.mu=0.4"]


def _drawn(err):
    return {what for what in ("modes:", "responses:", "stage contact ...") if what in err}


def test_the_library_draws_its_bars_only_where_asked(capsys):
    case = load(PAD, FRICTION)
    transient.cea(case)
    assert _drawn(capsys.readouterr().err) == set()
    with progress.shown():
        transient.cea(case)
    assert _drawn(capsys.readouterr().err) == {"modes:", "responses:", "stage contact ..."}


@pytest.mark.parametrize("json", [False, True])
def test_the_command_line_draws_them_on_a_terminal_not_for_json(json, capsys, monkeypatch):
    monkeypatch.setattr(commands, "_interactive", lambda: True)
    args = ["cea", PAD] + [a for o in FRICTION for a in ("--set", o)]
    assert commands.main(args + (["--json"] if json else [])) == 0
    err = capsys.readouterr().err
    assert _drawn(err) == (set() if json else {"modes:", "responses:", "stage contact ..."})
    if not json:
        # each stage said as it starts, then as it ends
        assert err.index("stage contact ...") < err.index("stage contact:")
