"""The name the command lines give themselves in usage and help (modal.cli_name): the console script's own, or
``python -m ...``."""
import subprocess
import sys
from pathlib import Path

import pytest

from support.paths import ROOT

SCRIPTS = Path(sys.executable).parent


@pytest.mark.parametrize("script, module, command", [("modalbal", "modal", "fit"), ("modalbal-scene", "balancer", "run")])
def test_console_scripts_print_their_own_name(script, module, command):
    path = SCRIPTS / script
    if not path.exists():
        pytest.skip(f"{script} is not installed beside {sys.executable} (pip install -e . makes it)")
    usage = subprocess.run([str(path), command], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert usage.returncode == 2 and usage.stderr.startswith(f"usage: {script} {command} "), usage.stderr
    assert "python -m" not in usage.stderr
    help_text = subprocess.run([str(path), "--help"], capture_output=True, text=True, cwd=ROOT, timeout=120).stdout
    assert help_text.startswith(f"usage: {script} "), help_text
    by_module = subprocess.run([sys.executable, "-m", module, command], capture_output=True, text=True, cwd=ROOT,
                               timeout=120)
    assert by_module.stderr.startswith(f"usage: python -m {module} {command} "), by_module.stderr


def test_a_caller_passing_arguments_gets_the_module_name(monkeypatch):
    from modal.cli_name import program_name

    monkeypatch.setattr(sys, "argv", ["/opt/venv/bin/modalbal", "fit"])
    assert program_name("modal") == "modalbal" and program_name("modal", ["fit"]) == "python -m modal"
    monkeypatch.setattr(sys, "argv", ["/src/modal/__main__.py", "fit"])
    assert program_name("modal") == "python -m modal"
