"""The registry's rows say whether a policy is an oracle as a field, and it agrees with the class (the one that
reads the true scene)."""

import pytest

from slax_drake.policies.registry import POLICY_NAMES, POLICY_TABLE, is_oracle


@pytest.mark.parametrize("name", POLICY_NAMES)
def test_the_oracle_flag_agrees_with_the_class(name):
    assert is_oracle(name) is POLICY_TABLE[name].oracle is bool(POLICY_TABLE[name].load().needs_true_scene)


def test_an_unknown_name_is_no_oracle():
    assert not is_oracle("oracle-unknown")
