"""The README's "first real measurement" walkthrough run as written, and its list of documentation (issue 20:
what a new user meets first; tests/test_first_use.py holds the rest)."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np

from support.cli import run_module

ROOT = Path(__file__).resolve().parents[1]


# ---- the README's "first real measurement" walkthrough ----------------------------------------------------------

_WORDS = {w: n for n, w in enumerate("zero one two three four five six seven eight nine ten eleven twelve".split())}


def _same_as_printed(readme: str, tool: float) -> bool:
    """A number of the README is the tool's value rounded to the README's digits: within half a unit of its last digit
    (the tool's own printout rounds to 5-6 significant digits, far finer)."""
    digits = len(readme.split(".")[1]) if "." in readme else 0
    return abs(float(readme) - tool) <= 0.5 * 10.0 ** -digits * (1 + 1e-6) + 1e-5 * abs(tool)


def _walkthrough_items(section: str) -> dict[int, str]:
    """The numbered paragraphs of the walkthrough, each as one line of text."""
    items, current = {}, None
    for line in section.splitlines():
        head = re.match(r"(\d+)\. (.*)", line)
        if head:
            current = int(head.group(1))
            items[current] = head.group(2)
        elif current is not None and line.startswith("   "):
            items[current] += " " + line.strip()
        else:
            current = None
    return items


def _mode_table(stdout: str) -> dict[int, tuple[float, set[str]]]:
    """The printed mode table: mode number -> (natural frequency in Hz, the flags of every channel)."""
    modes: dict[int, tuple[float, set[str]]] = {}
    for line in stdout.splitlines():
        row = re.match(r"\s+(\d+)\s+([\d.]+) ± .*\s(\S+)$", line)
        if row:
            flags = set() if row.group(3) == "-" else set(row.group(3).split(","))
            number = int(row.group(1))
            modes[number] = (float(row.group(2)), modes.get(number, (0.0, set()))[1] | flags)
    return modes


#: flags about where the response was measured (the walkthrough's third command is about the driving point);
#: driving_point_unknown replaced driving_point_assumed where nothing says which channel is the driving point
_DRIVING_POINT_FLAGS = {"not_driving_point", "driving_point_assumed", "driving_point_unknown"}


def test_readme_walkthrough_runs_as_written_and_its_numbers_are_the_tools(tmp_path):
    """Each command of the README's walkthrough, run as written from the project folder (the venv's python is
    this interpreter, out/ lies in a temporary folder), exits 0 and gives what the text says: every number and flag
    the text gives is the one the tool prints, rounded as written. The first command of each program runs in a
    process of its own; a program's later commands call the same ``main`` in this process."""
    import glob
    import importlib.util
    import json
    import shlex

    text = (ROOT / "README.md").read_text()
    section = text.split("## A first real measurement", 1)[1].split("\n## ", 1)[0]
    block = section.split("```sh\n", 1)[1].split("```", 1)[0]
    items = _walkthrough_items(section)
    out = tmp_path / "out"
    outputs = []
    started = set()  # programs already run in a process of their own
    for line in block.strip().splitlines():
        words = shlex.split(line.replace("out/", f"{out.as_posix()}/"))
        if words[0] == "mkdir":
            out.mkdir()
            continue
        assert words[0] == ".venv/bin/python", line
        args = [w for word in words[1:] for w in (sorted(glob.glob(word, root_dir=ROOT)) or [word])]
        if args[0] == "-m" and args[1] in started:  # the program's main once more, here (support.cli)
            done = run_module(*args[1:], cwd=ROOT)
        else:
            started.add(args[1])
            done = subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=ROOT, timeout=180)
        assert done.returncode == 0, (line, done.stderr)
        outputs.append(done.stdout)
    fit, again, driving, hammer = outputs
    assert (out / "beam.png").stat().st_size > 0 and (out / "beam.h5").exists()

    # 1. the global fit: how many modes, how many clean, each frequency named, and the flags named
    assert "method: global" in fit
    modes = _mode_table(fit)
    count = re.search(r"prints (\w+) modes, (\w+)\s+of them\s+flagged `(\w+)`.*Apart from that flag, (\w+) clean ones",
                      items[1], re.S)
    common = count.group(3)
    flagged = [f for f, flags in modes.values() if common in flags]
    clean = [f for f, flags in modes.values() if not flags - _DRIVING_POINT_FLAGS - {common}]
    count = (count.group(1), count.group(2), count.group(4))
    assert ([_WORDS[c] for c in count] == [len(modes), len(flagged), len(clean)]), (items[1], modes)
    named = re.findall(r"\d+\.\d+(?= Hz|,| and)", items[1])
    assert len(named) == len(modes), (named, modes)
    for (f_tool, _), f_readme in zip(sorted(modes.values()), sorted(named, key=float)):
        assert _same_as_printed(f_readme, f_tool), (f_readme, f_tool)
    flags_named = set(re.findall(r"`(\w+)`", items[1])) - {"auto"}
    assert flags_named == set().union(*(flags for _, flags in modes.values())) - _DRIVING_POINT_FLAGS
    # 2. the archive fitted again gives the same modes
    again_hz = sorted({m["natural_frequency_hz"] for m in json.loads(again)["modes"]})
    assert np.allclose(again_hz, sorted(f for f, _ in modes.values()), atol=1e-3), again_hz
    # 3. file 1 declared a driving point: its constants (those the text quotes) change sign, every mode is flagged
    # driving_point_contradicted and none has k, c, m (driving_point_unknown is what the text says an undeclared
    # driving point gives: the first command's files hold no point ids and declare none)
    named = set(re.findall(r"`(\w+)`", items[3]))
    assert "k [N/m]" in driving and all(flag in driving for flag in named - {"driving_point_unknown"})
    assert "driving_point_unknown" in named and "driving_point_unknown" not in driving
    assert all("driving_point_unknown" in flags for _, flags in modes.values()), modes
    rows = [line.split() for line in driving.splitlines() if re.match(r"\s+\d+\s+\d", line)]
    quoted = re.search(r"\(([-\d., ]+) 1/kg", items[3]).group(1).split(", ")
    assert len(rows) == len(quoted) == 6, (rows, quoted)
    for row, constant in zip(rows, quoted):
        assert _same_as_printed(constant, complex(row[7]).real), (constant, row)
        assert row[8:11] == ["n/a"] * 3 and "driving_point_contradicted" in row[-1], row
    # 4. the hammer scene: the truth is the generator's, the printed k, c, M are the tool's, and the text's claim
    # about them holds
    spec = importlib.util.spec_from_file_location("generate", ROOT / "data" / "synthetic" / "generate.py")
    generate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate)
    hits = re.findall(r"(\w+) hits", items[4])
    assert hits and all((_WORDS[n] if n in _WORDS else int(n)) == len(generate.HAMMER_HIT_TIMES_S) for n in hits), hits
    assert f"{len(generate.HAMMER_HIT_TIMES_S)} average(s)" in hammer and "0 hit(s) rejected" in hammer
    truth, printed = items[4].split("It prints")
    balls = 2 * 0.02  # the scene's [adb] n x m: the test was made with the balls in
    true = {"k": generate.RIG_STIFFNESS_N_PER_M, "c": generate.RIG_DAMPING_N_S_PER_M, "M": generate.RIG_MASS_KG - balls}
    units = {"k": "N/m", "c": "N s/m", "M": "kg"}
    within = _WORDS[re.search(r"each within (\w+) standard error", printed).group(1)]
    for name in true:
        assert _same_as_printed(re.search(rf"\b{name} = ([\d.]+) {units[name]}", truth).group(1), true[name])
        value, std = re.search(rf"\b{name} = ([\d.]+) ± ([\d.]+) {units[name]}", printed).groups()
        tool_value, tool_std = re.search(rf"\b{name} = ([\d.e+]+) {units[name]} \(± ([\d.e+]+)\)", hammer).groups()
        assert _same_as_printed(value, float(tool_value)) and _same_as_printed(std, float(tool_std)), (name, hammer)
        assert abs(float(tool_value) - true[name]) < within * float(tool_std), (name, tool_value, true[name])
    assert (out / "hammer.h5").exists() and (out / "hammer_plots" / "frf_estimate.png").exists()


def test_the_documentation_list_names_every_doc():
    """The README's list of documentation names every page in docs/, and only pages that exist."""
    text = (ROOT / "README.md").read_text()
    section = text.split("## Documentation and benchmarks", 1)[1].split("\n## ", 1)[0]
    listed = set(re.findall(r"^- `docs/([\w.-]+\.md)`", section, flags=re.M))
    assert listed == {p.name for p in (ROOT / "docs").glob("*.md")}
