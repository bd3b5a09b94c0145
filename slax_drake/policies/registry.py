"""Policies by name, built for a scenario: the one place that maps a command-line name to a policy object."""

from __future__ import annotations

import dataclasses
import typing

from slax_drake.errors import UserError

# The action model, the distributions and the scene sampler (OpenCV, shapely, trimesh, torch) are imported where
# used: the command-line parser imports this module for add_tool_rule_argument and POLICY_NAMES.
if typing.TYPE_CHECKING:
    from slax_drake.config import Scenario
    from slax_drake.policies.actions import ToolConfig

POLICY_NAMES = ("oracle-p", "oracle-p+s", "dar", "der-3", "bluction-dar", "bluction-dar-cost", "bluction-la2")


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


def refuse_other_rules(path, tool_rules: dict, error=UserError, kind: str = "result file") -> None:
    """Raises ``error`` when the result file at ``path`` (a benchmark's per-trial JSON, which records its rule
    variants under "tool_rules") is unreadable or was made under rules other than ``tool_rules``."""
    import json
    from pathlib import Path

    try:
        made_with = json.loads(Path(path).read_text()).get("tool_rules") or {}
    except (OSError, json.JSONDecodeError, AttributeError) as e:
        raise error(f"{path}: unreadable {kind} ({e}); delete it to rerun that trial") from None
    if made_with != tool_rules:
        raise error(f"{path} was made with tool rules {made_with}, not {tool_rules}: use another --out")


def tool_config(scenario: Scenario, **overrides) -> ToolConfig:
    from slax_drake.policies.actions import ToolConfig

    return ToolConfig(object_density=scenario.objects.density, clearance=scenario.objects.clearance, **overrides)


def make_policy(name: str, scenario: Scenario, perception: str = "ground-truth", horizon: int | None = None,
                target_size=None, tool_overrides: dict | None = None, oracle_options: dict | None = None):
    """A fresh policy object named ``name`` (see POLICY_NAMES) for ``scenario``'s shelf and camera."""
    from slax_drake.policies.actions import ActionModel
    from slax_drake.policies.distribution import make_distribution_model
    from slax_drake.policies.oracle import Oracle
    from slax_drake.policies.policies import DAR, DER, BluctionDAR, BluctionLookahead
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.sampling import shelf_of

    if name not in POLICY_NAMES:
        raise UnknownPolicyError(f"unknown policy '{name}' (known: {', '.join(POLICY_NAMES)})")
    psi = scenario.protocol.suction_cost
    model = ActionModel(shelf_of(scenario), Camera.from_config(scenario.camera).position,
                        tool_config(scenario, **(tool_overrides or {})))
    if name.startswith("oracle"):
        return Oracle(model, suctions=name == "oracle-p+s", psi=psi, horizon=horizon,
                      threshold=scenario.target.visibility_threshold, **(oracle_options or {}))
    size = target_size or tuple(scenario.target.sizes[0])
    dist = make_distribution_model(perception, size)
    if name == "dar":
        return DAR(model, dist, psi=psi)
    if name == "der-3":
        return DER(model, dist, psi=psi, depth=3)
    if name == "bluction-dar":
        return BluctionDAR(model, dist, psi=psi, suction_weighting="paper")
    if name == "bluction-dar-cost":
        return BluctionDAR(model, dist, psi=psi, suction_weighting="cost")
    if name == "bluction-la2":
        return BluctionLookahead(model, dist, psi=psi)
    raise AssertionError(name)
