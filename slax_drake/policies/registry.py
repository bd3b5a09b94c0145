"""Policies by name, built for a scenario: the one place that maps a command-line name to a policy object.

:data:`POLICY_TABLE` is the table: name -> (class, options). A distribution policy's class is called as
``cls(action_model, distribution_model, psi=psi, **options)``, an oracle's (``needs_true_scene``) as
``cls(action_model, psi=psi, horizon=horizon, threshold=v, **options)``. Every class implements
:class:`slax_drake.policies.protocol.Policy`. Classes are named by import path so that listing the names imports
nothing heavy. A new policy is one class and one line here.
"""

from __future__ import annotations

import dataclasses
import importlib
import typing

from slax_drake.errors import UserError

# The action model, the distributions and the scene sampler (OpenCV, shapely, trimesh, torch) are imported where
# used: the command-line parser imports this module for add_tool_rule_argument and POLICY_NAMES.
if typing.TYPE_CHECKING:
    from slax_drake.config import Scenario
    from slax_drake.policies.actions import ToolConfig



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
    "dar": PolicyEntry(f"{_POLICIES}:DAR"),
    "der-3": PolicyEntry(f"{_POLICIES}:DER", {"depth": 3}),
    "bluction-dar": PolicyEntry(f"{_POLICIES}:BluctionDAR", {"suction_weighting": "paper"}),
    "bluction-dar-cost": PolicyEntry(f"{_POLICIES}:BluctionDAR", {"suction_weighting": "cost"}),
    "bluction-la2": PolicyEntry(f"{_POLICIES}:BluctionLookahead"),
}
POLICY_NAMES = tuple(POLICY_TABLE)
PAPER_POLICIES = ("oracle-p", "oracle-p+s", "dar", "der-3", "bluction-dar")  # the five of the paper's Table I
OUR_POLICIES = ("bluction-la2",)  # the project's own
DEFAULT_BENCHMARK_POLICIES = PAPER_POLICIES + OUR_POLICIES



class UnknownPolicyError(UserError):
    """A policy name that does not exist."""


def add_tool_rule_argument(parser, note: str) -> None:
    """The repeatable ``--tool-rule FIELD=VALUE`` option of the commands that run the action model (read it with
    :func:`parse_tool_rules`); ``note`` says what the rules apply to."""
    parser.add_argument("--tool-rule", action="append", default=[], metavar="FIELD=VALUE",
                        help="an action-model rule variant, a ToolConfig field of slax_drake/policies/actions.py "
                        f"(e.g. max_suction_moment=0.4); repeatable; {note}")


def parse_tool_rules(items) -> dict:
    """``["max_suction_moment=0.4", "tube_approach_check=false"]`` -> typed ToolConfig overrides; UserError for an
    unknown field or a value of the wrong type."""
    from slax_drake.policies.actions import ToolConfig, tool_config_problem

    fields = [f.name for f in dataclasses.fields(ToolConfig)]
    defaults = ToolConfig()
    rules = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        key, text = key.strip(), text.strip()
        if not sep or key not in fields:
            raise UserError(f"--tool-rule takes FIELD=VALUE with a ToolConfig field (got {item!r}; fields: "
                            f"{', '.join(fields)})")
        kind = type(getattr(defaults, key))
        try:
            if kind is bool:
                if text.lower() not in ("true", "false"):
                    raise ValueError(text)
                value = text.lower() == "true"
            else:
                value = kind(text)
        except ValueError:
            raise UserError(f"--tool-rule {key} needs a {kind.__name__} (got {text!r})") from None
        rules[key] = value
    problem = tool_config_problem(ToolConfig(**rules))
    if problem:
        raise UserError(f"--tool-rule {problem}")
    return rules


def without_defaults(rules: dict) -> dict:
    """``rules`` less the entries equal to ToolConfig's first-order defaults, so that one set of rules has one
    record (``max_suction_moment=inf`` is the default rule, recorded as no variant)."""
    from slax_drake.policies.actions import ToolConfig

    defaults = ToolConfig()
    return {k: v for k, v in rules.items() if getattr(defaults, k) != v}


def tool_config(scenario: Scenario, **overrides) -> ToolConfig:
    from slax_drake.policies.actions import ToolConfig

    return ToolConfig(object_density=scenario.objects.density, clearance=scenario.objects.clearance, **overrides)


def make_policy(name: str, scenario: Scenario, perception: str = "ground-truth", horizon: int | None = None,
                target_size=None, tool_overrides: dict | None = None, oracle_options: dict | None = None):
    """A fresh policy object named ``name`` (a key of :data:`POLICY_TABLE`) for ``scenario``'s shelf and camera.
    ``oracle_options``: extra constructor options of the oracles (e.g. ``max_expansions``)."""
    from slax_drake.policies.actions import ActionModel
    from slax_drake.policies.distribution import make_distribution_model
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.sampling import shelf_of

    entry = POLICY_TABLE.get(name)
    if entry is None:
        raise UnknownPolicyError(f"unknown policy '{name}' (known: {', '.join(POLICY_NAMES)})")
    cls = entry.load()
    psi = scenario.protocol.suction_cost
    model = ActionModel(shelf_of(scenario), Camera.from_config(scenario.camera).position,
                        tool_config(scenario, **(tool_overrides or {})))
    if cls.needs_true_scene:
        return cls(model, psi=psi, horizon=horizon, threshold=scenario.target.visibility_threshold,
                   **entry.options, **(oracle_options or {}))
    size = target_size or tuple(scenario.target.sizes[0])
    return cls(model, make_distribution_model(perception, size), psi=psi, **entry.options)
