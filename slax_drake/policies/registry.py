"""Policies by name, built for a scenario: the one place that maps a command-line name to a policy object."""

from __future__ import annotations

from slax_drake.config import Scenario
from slax_drake.errors import UserError
from slax_drake.policies.actions import ActionModel
from slax_drake.policies.rules import PROFILES, RULES, ToolConfig, flat_field_names, tool_config_problem
from slax_drake.policies.distribution import make_distribution_model
from slax_drake.scene.camera import Camera
from slax_drake.scene.sampling import shelf_of

POLICY_NAMES = ("oracle-p", "oracle-p+s", "dar", "der-3", "bluction-dar", "bluction-dar-cost", "bluction-la2")


class UnknownPolicyError(UserError):
    """A policy name that does not exist."""


def add_tool_rule_argument(parser, note: str) -> None:
    """The ``--profile NAME`` option and the repeatable ``--tool-rule FIELD=VALUE`` option of the commands that run
    the action model (read them with :func:`parse_tool_rules`); ``note`` says what the rules apply to."""
    parser.add_argument("--profile", choices=PROFILES, default=None,
                        help="the action model's rule profile: 'paper' (the paper's first-order simulator) or "
                        "'station' (our physical tool); default: the scenario's 'profile'")
    parser.add_argument("--tool-rule", action="append", default=[], metavar="FIELD=VALUE",
                        help="override one rule of the profile (a rule of slax_drake/policies/rules.py, e.g. "
                        "max_suction_moment=0.4 or blade_gap=0.035) or a geometry/discretisation field; "
                        f"repeatable; {note}")


def parse_tool_rules(items, profile: str = "station") -> dict:
    """``["max_suction_moment=0.4", "tube_approach_check=false"]`` -> typed overrides of ``profile``'s rules (or
    of a geometry/discretisation field); UserError for an unknown field or a value of the wrong type."""
    fields = flat_field_names()
    defaults = ToolConfig.build(profile)
    rules = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        key, text = key.strip(), text.strip()
        if not sep or key not in fields:
            raise UserError(f"--tool-rule takes FIELD=VALUE with a rule or tool field (got {item!r}; fields: "
                            f"{', '.join(fields)})")
        kind = RULES[key].type if key in RULES else type(defaults.value(key))
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
    problem = tool_config_problem(ToolConfig.build(profile, **rules))
    if problem:
        raise UserError(f"--tool-rule {problem}")
    return rules


def without_defaults(rules: dict, profile: str = "station") -> dict:
    """``rules`` less the entries equal to ``profile``'s values, so that one set of rules has one record
    (``max_suction_moment=inf`` is both profiles' value, recorded as no override)."""
    defaults = ToolConfig.build(profile)
    return {k: v for k, v in rules.items() if defaults.value(k) != v}


def scenario_profile(scenario: Scenario, profile: str | None = None) -> str:
    """The profile a run uses: ``profile`` when given (``--profile``), else the scenario's."""
    return profile or scenario.profile


def refuse_other_rules(path, tool_rules: dict, error=UserError, kind: str = "result file",
                       profile: str = "station") -> None:
    """Raises ``error`` when the result file at ``path`` (a benchmark's per-trial JSON, which records its profile
    under "profile" and its rule overrides under "tool_rules") is unreadable or was made under another profile or
    other rules. A file without "profile" predates the profiles: its rules were the station's."""
    import json
    from pathlib import Path

    try:
        data = json.loads(Path(path).read_text())
        made_with = data.get("tool_rules") or {}
        made_profile = data.get("profile") or "station"
    except (OSError, json.JSONDecodeError, AttributeError) as e:
        raise error(f"{path}: unreadable {kind} ({e}); delete it to rerun that trial") from None
    if made_profile != profile:
        raise error(f"{path} was made with the '{made_profile}' profile, not '{profile}': use another --out")
    if made_with != tool_rules:
        raise error(f"{path} was made with tool rules {made_with}, not {tool_rules}: use another --out")


def tool_config(scenario: Scenario, profile: str | None = None, **overrides) -> ToolConfig:
    """The action model's configuration for ``scenario``: its profile (or ``profile``), its objects' density
    and clearance, and single ``overrides`` (flat names, see ToolConfig.build)."""
    return ToolConfig.build(scenario_profile(scenario, profile), object_density=scenario.objects.density,
                            clearance=scenario.objects.clearance, **overrides)


def make_policy(name: str, scenario: Scenario, perception: str = "ground-truth", horizon: int | None = None,
                target_size=None, tool_overrides: dict | None = None, oracle_options: dict | None = None,
                profile: str | None = None):
    """A fresh policy object named ``name`` (see POLICY_NAMES) for ``scenario``'s shelf and camera, planning with
    ``profile``'s rules (default: the scenario's) and ``tool_overrides``."""
    from slax_drake.policies.oracle import Oracle
    from slax_drake.policies.policies import DAR, DER, BluctionDAR, BluctionLookahead

    if name not in POLICY_NAMES:
        raise UnknownPolicyError(f"unknown policy '{name}' (known: {', '.join(POLICY_NAMES)})")
    psi = scenario.protocol.suction_cost
    model = ActionModel(shelf_of(scenario), Camera.from_config(scenario.camera).position,
                        tool_config(scenario, profile, **(tool_overrides or {})))
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
