"""Search policies in a fast first-order shelf simulator: the bluction tool's action model, the simulator,
DAR, DER-k, Bluction-DAR, the oracles, and the Table I benchmark runner."""

from slax_drake.policies.actions import ActionModel, Push, Rejected, Suction, apply_action
from slax_drake.policies.rules import ToolConfig
from slax_drake.policies.distribution import DistributionModel, GroundTruthDistribution
from slax_drake.policies.registry import POLICY_NAMES, make_policy
from slax_drake.policies.simulator import Observation, TrialResult, execute, observe, run_trial

__all__ = [
    "ActionModel", "DistributionModel", "GroundTruthDistribution", "Observation", "POLICY_NAMES", "Push",
    "Rejected", "Suction", "ToolConfig", "TrialResult", "apply_action", "execute", "make_policy", "observe",
    "run_trial",
]
