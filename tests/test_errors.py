"""One errors module: every exception of the package is defined in slax_drake/errors.py under one of two bases, and
the command line treats them differently (a user error is one line and exit code 2; an internal fault keeps its
traceback)."""

import ast
import inspect
from pathlib import Path

import pytest

import slax_drake.errors as errors
from slax_drake.cli import main

PACKAGE = Path(errors.__file__).parent


def _exception_classes():
    return [c for _, c in inspect.getmembers(errors, inspect.isclass) if issubclass(c, Exception)]


def test_every_exception_class_is_defined_in_the_errors_module():
    elsewhere = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name == "errors.py" and path.parent == PACKAGE:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef) and (node.name.endswith("Error") or node.name.endswith("Exception")):
                elsewhere.append(f"{path.relative_to(PACKAGE.parent)}: {node.name}")
    assert not elsewhere, "exception classes outside slax_drake/errors.py:\n" + "\n".join(elsewhere)


def test_every_exception_is_either_a_user_error_or_an_internal_fault():
    for cls in _exception_classes():
        if cls in (errors.UserError, errors.InternalError):
            continue
        assert issubclass(cls, errors.UserError) != issubclass(cls, errors.InternalError), cls.__name__


def test_a_ruckig_failure_is_an_internal_fault_not_the_users_mistake():
    assert issubclass(errors.TimingError, errors.InternalError)
    assert not issubclass(errors.TimingError, errors.UserError)


@pytest.mark.parametrize("raised, code", [(errors.ConfigError("bad key"), 2), (errors.TimingError("no profile"), None)])
def test_the_command_line_prints_user_errors_and_lets_internal_faults_through(monkeypatch, capsys, raised, code):
    import slax_drake.scene.commands as scene_commands

    def fail(args):
        raise raised

    monkeypatch.setattr(scene_commands, "run", fail)
    if code is None:
        with pytest.raises(errors.TimingError, match="no profile"):  # the traceback reaches the user
            main(["scene", "--out", "/tmp/unused.json"])
    else:
        assert main(["scene", "--out", "/tmp/unused.json"]) == code
        assert capsys.readouterr().err.strip() == "slax-drake scene: error: bad key"
