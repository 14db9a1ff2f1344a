"""Help texts that promise what a command does: they must say what the code does."""

from __future__ import annotations

from robot.cli.main import main
from robot.cli.registry import SUMMARIES


def test_the_paper_summary_lists_every_output():
    # clearance paper writes figures 7, 8, 9 and 10, summary.json, claims.md and the animation
    summary = SUMMARIES["paper"]
    assert "7-10" in summary and "claims.md" in summary and "summary.json" in summary


def test_animate_help_states_the_range_of_exaggerate_and_the_mechanism_lookup(capsys):
    assert main(["animate", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "1 <= K <= 1e6" in out
    assert "the file the run read, else the shipped file of that name" in out
