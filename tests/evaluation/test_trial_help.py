"""``trial --help`` tells a newcomer which policies exist and what --perception chooses."""

from __future__ import annotations

import pytest

from slax_drake.cli import main
from slax_drake.policies.registry import POLICY_NAMES


def test_trial_help_lists_the_policies_and_describes_perception(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["trial", "--help"])
    assert exit_.value.code == 0
    text = " ".join(capsys.readouterr().out.split()).replace("- ", "-")
    for name in POLICY_NAMES:
        assert name in text
    after = text.split("--perception {ground-truth,learned}")[-1]
    assert "occupancy distribution" in after and "network" in after
