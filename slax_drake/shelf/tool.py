"""The action model's tool configuration for a run: the rule profile a scenario (or ``--profile``) names, the
scenario's object density, clearance and mass model, and single ``--tool-rule FIELD=VALUE`` overrides.

The commands that run the action model (the shelf simulator, the Drake trial, the hardware checks) share these
options and this one way of building a :class:`~slax_drake.shelf.rules.ToolConfig` from them. The module imports
only the rules (plain data): the command-line parser imports it for :func:`add_tool_rule_argument`.
"""

from __future__ import annotations

import typing

from slax_drake.errors import UserError
from slax_drake.shelf.rules import PROFILES, RULES, ToolConfig, flat_field_names, tool_config_problem

if typing.TYPE_CHECKING:
    from slax_drake.config import Scenario


def add_tool_rule_argument(parser, note: str) -> None:
    """The ``--profile NAME`` option and the repeatable ``--tool-rule FIELD=VALUE`` option of the commands that run
    the action model (read them with :func:`parse_tool_rules`); ``note`` says what the rules apply to."""
    parser.add_argument("--profile", choices=PROFILES, default=None,
                        help="the action model's rule profile: 'paper' (the paper's first-order simulator) or "
                        "'station' (our physical tool); default: the scenario's 'profile'")
    parser.add_argument("--tool-rule", action="append", default=[], metavar="FIELD=VALUE",
                        help="override one rule of the profile (a rule of slax_drake/shelf/rules.py, e.g. "
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


def tool_config(scenario: Scenario, profile: str | None = None, **overrides) -> ToolConfig:
    """The action model's configuration for ``scenario``: its profile (or ``profile``), its objects' density,
    clearance and mass model, and single ``overrides`` (flat names, see ToolConfig.build)."""
    physics = scenario.physics
    fields = dict(object_density=scenario.objects.density, clearance=scenario.objects.clearance,
                  mass_model=physics.mass_model, box_masses=tuple(tuple(r) for r in physics.box_masses),
                  cylinder_masses=tuple(tuple(r) for r in physics.cylinder_masses))
    fields.update(overrides)  # e.g. --tool-rule clearance=0: the action model's, not the scene sampler's
    return ToolConfig.build(scenario_profile(scenario, profile), **fields)
