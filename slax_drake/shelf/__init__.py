"""The action model of the shelf and the bluction tool, and the first-order shelf simulator: the domain model
that the policies, motion planning and the hardware checks stand on.

- :mod:`~slax_drake.shelf.actions`: pushes and suctions, their footprints and outcomes (:class:`ActionModel`);
- :mod:`~slax_drake.shelf.rules`: the tool's rules and their two profiles (:class:`ToolConfig`);
- :mod:`~slax_drake.shelf.tool`: the tool configuration of a run (scenario, ``--profile``, ``--tool-rule``);
- :mod:`~slax_drake.shelf.floor`, :mod:`~slax_drake.shelf.visibility`, :mod:`~slax_drake.shelf.reach`: the shelf
  floor's free space, the target's occlusion, the station's reach map;
- :mod:`~slax_drake.shelf.simulator` and :mod:`~slax_drake.shelf.distribution`: the first-order simulator (observe,
  execute, check the target's visibility) and the occupancy distributions it hands the policies.

The names below are imported from their submodule on first use (:mod:`slax_drake.lazy_exports`)."""

from slax_drake.lazy_exports import lazy_exports

_EXPORTS = {
    "ActionModel": "actions", "Push": "actions", "Rejected": "actions", "Suction": "actions", "ToolConfig": "rules",
    "apply_action": "actions", "tool_config": "tool",
    "DistributionModel": "distribution", "GroundTruthDistribution": "distribution",
    "PolicyObservation": "simulator", "TrialResult": "simulator", "execute": "simulator", "observe": "simulator",
    "run_trial": "simulator",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
