"""Search policies in a fast first-order shelf simulator: the bluction tool's action model, the simulator,
DAR, DER-k, Bluction-DAR, the oracles, and the Table I benchmark runner.

The names below are imported from their submodule on first use (:mod:`slax_drake.lazy_exports`)."""

from slax_drake.lazy_exports import lazy_exports

_EXPORTS = {
    "ActionModel": "actions", "Push": "actions", "Rejected": "actions", "Suction": "actions", "ToolConfig": "rules",
    "apply_action": "actions",
    "DistributionModel": "distribution", "GroundTruthDistribution": "distribution",
    "POLICY_NAMES": "registry", "make_policy": "registry",
    "Observation": "simulator", "TrialResult": "simulator", "execute": "simulator", "observe": "simulator",
    "run_trial": "simulator",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
