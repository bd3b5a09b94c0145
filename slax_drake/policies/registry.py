"""Policies by name, built for a scenario: the one place that maps a command-line name to a policy object.

:data:`POLICY_TABLE` is the table: name -> (class, options). A distribution policy's class is called as
``cls(action_model, distribution_model, psi=psi, **options)`` (plus ``horizon=horizon`` for a class with
``uses_horizon``), an oracle's (``needs_true_scene``) as
``cls(action_model, psi=psi, horizon=horizon, threshold=v, **options)``. Every class implements
:class:`slax_drake.policies.protocol.Policy`. Classes are named by import path so that listing the names imports
nothing heavy. A new policy is one class and one line here.
"""

from __future__ import annotations

import dataclasses
import importlib
import typing

from slax_drake.errors import UnknownPolicyError

# The action model, the distributions and the scene sampler (OpenCV, shapely, trimesh, torch) are imported where
# used: the command-line parser imports this module for POLICY_NAMES.
if typing.TYPE_CHECKING:
    from slax_drake.config import Scenario


@dataclasses.dataclass(frozen=True)
class PolicyEntry:
    """One row of the policy table: ``cls`` as "module:Class" and the options its constructor gets."""

    cls: str
    options: dict = dataclasses.field(default_factory=dict)

    def load(self) -> type:
        module, _, name = self.cls.partition(":")
        return getattr(importlib.import_module(module), name)


_POLICIES = "slax_drake.policies.policies"
POLICY_TABLE: dict[str, PolicyEntry] = {
    "oracle-p": PolicyEntry("slax_drake.policies.oracle:Oracle", {"suctions": False}),
    "oracle-p+s": PolicyEntry("slax_drake.policies.oracle:Oracle", {"suctions": True}),
    # DAR and Bluction-DAR with the corrections any implementation needs (policies.py's docstring: a failed action
    # is excluded, no return to an observed arrangement, no zero-reduction action while another reveals unseen
    # space); the "-literal" rows are the paper's text alone, kept so that the corrections' effect is visible.
    "dar": PolicyEntry(f"{_POLICIES}:DAR", {"corrected": True}),
    "dar-literal": PolicyEntry(f"{_POLICIES}:DAR", {"corrected": False}),
    "der-3": PolicyEntry(f"{_POLICIES}:DER", {"depth": 3}),
    "bluction-dar": PolicyEntry(f"{_POLICIES}:BluctionDAR", {"suction_weighting": "paper", "corrected": True}),
    "bluction-dar-literal": PolicyEntry(f"{_POLICIES}:BluctionDAR", {"suction_weighting": "paper", "corrected": False}),
    "bluction-dar-cost": PolicyEntry(f"{_POLICIES}:BluctionDAR", {"suction_weighting": "cost", "corrected": True}),
    "bluction-la2": PolicyEntry(f"{_POLICIES}:BluctionLookahead"),
    "slax-hindsight": PolicyEntry("slax_drake.policies.hindsight:Hindsight"),
    "slax-belief": PolicyEntry("slax_drake.policies.belief:BeliefSearch"),
    # camera mode (belief.py's docstring): hypotheses assumed 0.13 m deep, hidden ones remembered, outcome evidence
    # within 1 cm; the privileged path reads none of these. Measured, not the default (docs/research/slax_belief.md)
    "slax-belief-camera-depth": PolicyEntry("slax_drake.policies.belief:BeliefSearch",
                                            {"camera_depth": 0.13, "camera_memory": True,
                                             "camera_outcome_tolerance": 0.01}),
    # a failed placement's box refuses no later placement; one overlapping it in hidden space fails with 0.5
    # more (belief.py's blocked_rule="risk"). Measured, not the default (docs/research/slax_belief.md)
    "slax-belief-v4": PolicyEntry("slax_drake.policies.belief:BeliefSearch", {"blocked_rule": "risk"}),
    # slax-belief without remembered objects, actions' outcomes and the wider beam (belief.py's docstring)
    "slax-belief-v2": PolicyEntry("slax_drake.policies.belief:BeliefSearch",
                                  {"evidence": "none", "remember_objects": False, "widen_beam": 0}),
}
POLICY_NAMES = tuple(POLICY_TABLE)
PAPER_POLICIES = ("oracle-p", "oracle-p+s", "dar", "der-3", "bluction-dar")  # the five of the paper's Table I
LITERAL_POLICIES = ("dar-literal", "bluction-dar-literal")  # the paper's text without the corrections
OUR_POLICIES = ("bluction-la2", "slax-hindsight", "slax-belief")  # the project's own (slax-belief: our best)
DEFAULT_BENCHMARK_POLICIES = PAPER_POLICIES + OUR_POLICIES


def make_policy(name: str, scenario: Scenario, perception: str = "ground-truth", horizon: int | None = None,
                target_size=None, tool_overrides: dict | None = None, oracle_options: dict | None = None,
                profile: str | None = None, policy_options: dict | None = None):
    """A fresh policy object named ``name`` (a key of :data:`POLICY_TABLE`) for ``scenario``'s shelf and camera,
    planning with ``profile``'s rules (default: the scenario's) and ``tool_overrides``. ``oracle_options``: extra
    constructor options of the oracles (e.g. ``seconds``, the search time limit); ``policy_options``: extra
    constructor options of a distribution policy (e.g. ``seconds``, the hindsight policy's time per decision)."""
    from slax_drake.shelf.actions import ActionModel
    from slax_drake.shelf.distribution import make_distribution_model
    from slax_drake.shelf.tool import tool_config
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.sampling import shelf_of

    entry = POLICY_TABLE.get(name)
    if entry is None:
        raise UnknownPolicyError(f"unknown policy '{name}' (known: {', '.join(POLICY_NAMES)})")
    cls = entry.load()
    psi = scenario.protocol.suction_cost
    model = ActionModel(shelf_of(scenario), Camera.from_config(scenario.camera).position,
                        tool_config(scenario, profile, **(tool_overrides or {})))
    if cls.needs_true_scene:
        policy = cls(model, psi=psi, horizon=horizon, threshold=scenario.target.visibility_threshold,
                     **entry.options, **(oracle_options or {}))
    else:
        size = target_size or tuple(scenario.target.sizes[0])
        options = dict(entry.options, **(policy_options or {}))
        if getattr(cls, "uses_visibility_threshold", False):  # a policy that plans for the success test itself
            options.setdefault("threshold", scenario.target.visibility_threshold)
        if getattr(cls, "uses_horizon", False):  # a policy that plans to the protocol's deadline H, as the oracles
            options.setdefault("horizon", horizon)
        policy = cls(model, make_distribution_model(perception, size), psi=psi, **options)
    policy.name = name  # the table's row name (one class may serve several rows, e.g. "dar" and "dar-literal")
    return policy
