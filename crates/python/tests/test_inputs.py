"""The input side of the Python package: every command of the binary
reachable (or listed as deliberately not), the importers without files,
the editable spec, and systems that pickle."""

import multiprocessing
import pickle
import re
import subprocess
from pathlib import Path

import pytest

import rtpipe
from test_rtpipe import BIN, EXAMPLES, ROOT, without_clock

DATA = ROOT / "crates" / "cli" / "tests" / "data"
ULOG = ROOT / "crates" / "model" / "tests" / "data" / "px4" / "sample_log_small.ulg"


def binary(*args, check=True):
    if not BIN.exists():
        pytest.skip(f"no rtpipe binary at {BIN} (cargo build --release, or set RTPIPE_BIN)")
    out = subprocess.run([str(BIN), *map(str, args)], capture_output=True, text=True, check=False)
    if check:
        assert out.returncode == 0, out.stderr
    return out


# --- every command reachable ------------------------------------------------


def python_callable(name):
    owner, attr = name.split(".", 1)
    return getattr(rtpipe.System if owner == "System" else rtpipe, attr, None)


def test_every_registered_command_has_its_python_function_or_a_reason():
    assert rtpipe._rtpipe.REACH, "the registry lists the commands"
    for path, name, why in rtpipe._rtpipe.REACH:
        if name is None:
            assert why, f"{path}: deliberately not reachable, but no reason given"
        else:
            assert callable(python_callable(name)), f"{path}: no {name} in the package"


def commands_in_help(*words):
    """The subcommands `rtpipe WORDS --help` lists."""
    text = binary(*words, "--help").stdout
    listing = text.split("Commands:")[1].split("Options:")[0]
    names = [m.group(1) for m in re.finditer(r"^  (\S+)", listing, re.M)]
    return [n for n in names if n != "help"]


def test_every_command_of_the_binary_is_in_the_registry():
    paths = []
    for command in commands_in_help():
        if command in ("import", "generate"):
            paths += [f"{command} {sub}" for sub in commands_in_help(command)]
        else:
            paths.append(command)
    assert paths == [path for path, _, _ in rtpipe._rtpipe.REACH]


# --- import e2eeval, import px4-ulog ----------------------------------------


def test_import_e2eeval_gives_the_specs_the_binary_writes(tmp_path):
    yaml = DATA / "e2eeval-inter.yaml"
    binary("import", "e2eeval", yaml, tmp_path)
    written = {p.stem: p.read_text() for p in tmp_path.glob("*.toml")}
    systems = rtpipe.import_e2eeval(yaml)
    assert sorted(systems) == sorted(written)
    for name, system in systems.items():
        assert isinstance(system, rtpipe.System)
        assert system.to_toml() == rtpipe.load(tmp_path / f"{name}.toml").to_toml()
        assert system.analyze()["chains"] == rtpipe.load(tmp_path / f"{name}.toml").analyze()["chains"]


def test_import_e2eeval_takes_the_yaml_text_named_as_its_file():
    yaml = DATA / "e2eeval-inter.yaml"
    from_file = rtpipe.import_e2eeval(yaml)
    from_text = rtpipe.import_e2eeval(yaml.read_text(), name="e2eeval-inter.yaml")
    assert {k: v.to_toml() for k, v in from_text.items()} == {
        k: v.to_toml() for k, v in from_file.items()
    }


def test_a_bad_e2eeval_file_raises_with_its_place():
    with pytest.raises(rtpipe.InputError, match=r"bad\.yaml:\d+:\d+: "):
        rtpipe.import_e2eeval("Tasks: [\n  - !Task {period: \n", name="bad.yaml")


def test_import_px4_ulog_gives_the_spec_and_ages_the_binary_writes(tmp_path):
    binary("import", "px4-ulog", ULOG, tmp_path)
    got = rtpipe.import_px4_ulog(ULOG)
    assert got["system"].to_toml() == rtpipe.load(tmp_path / "spec.toml").to_toml()
    assert got["observed"] == (tmp_path / "observed.csv").read_text()
    assert got["ages"] and got["assumptions"] and got["board"]


def test_import_px4_ulog_refuses_a_bad_flag_naming_the_keyword():
    with pytest.raises(rtpipe.InputError) as e:
        rtpipe.import_px4_ulog(ULOG, px4_version="one")
    assert "px4_version" in str(e.value) and "--" not in str(e.value)


# --- the editable spec --------------------------------------------------------


def edited_file(tmp_path, old, new):
    """paper-table3.toml with one line changed, loaded from a file."""
    text = (EXAMPLES / "paper-table3.toml").read_text()
    assert text.count(old) == 1
    path = tmp_path / "edited.toml"
    path.write_text(text.replace(old, new))
    return rtpipe.load(path)


def test_tasks_stay_a_list_of_names():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    names = ["p1", "p2", "p3", "p4", "p5", "p6", "p7"]
    assert system.tasks == names and list(system.tasks) == names
    assert system.tasks[0] == "p1" and system.tasks[-1] == "p7" and len(system.tasks) == 7
    assert "p3" in system.tasks and system.chains == ["P1", "P2"]


def test_an_edited_period_is_what_the_next_analysis_uses(tmp_path):
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    before = system.analyze()
    system.tasks["p2"].period = "80ms"
    assert system.tasks["p2"].period == "80ms"
    after = system.analyze()
    assert after["chains"] != before["chains"]
    same = edited_file(tmp_path, "budget = 6\nperiod = 50", "budget = 6\nperiod = 80")
    assert without_clock(after) == without_clock(same.analyze())
    assert 'period = "80ms"' in system.to_toml()


def test_every_task_key_the_brief_names_edits(tmp_path):
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    task = system.tasks["p1"]
    task.exec = "9ms"
    task.budget = "11ms"
    task.deadline = "90ms"
    task.cpu = 0
    assert (task.exec, task.budget, task.deadline, task.cpu) == ("9ms", "11ms", "90ms", 0)
    del task.deadline
    assert task.deadline is None
    assert system.analyze()["schedulability"]


def test_a_chain_limit_edit_changes_the_verdict():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    system.chains["P1"].reaction = "1ms"
    report = system.analyze()
    assert report["chains"][0]["limit"] is not None and not report["ok"]
    assert report["exit_status"] == 1
    system.chains["P1"].reaction = None
    assert system.analyze()["ok"]


def test_a_rejected_edit_names_the_attribute_and_leaves_the_system_as_it_was():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    text = system.to_toml()
    with pytest.raises(rtpipe.InputError) as e:
        system.tasks["p1"].budget = 1
    said = str(e.value)
    assert said.startswith("error: system.tasks['p1'].budget = 1: budget 1 of task `p1`"), said
    assert e.value.help and "raise the budget" in e.value.help
    assert "line" not in said and ".toml:" not in said, said
    assert system.to_toml() == text
    with pytest.raises(rtpipe.InputError, match=r"system.tasks\['p1'\].period = '-1ms': period must be positive"):
        system.tasks["p1"].period = "-1ms"
    with pytest.raises(rtpipe.InputError, match=r"system.chains\['P1'\].reaction = 'soon'"):
        system.chains["P1"].reaction = "soon"
    assert system.to_toml() == text


def test_an_unknown_key_or_name_is_refused():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    with pytest.raises(AttributeError, match="has no key 'perod'"):
        system.tasks["p1"].perod = "1ms"
    with pytest.raises(KeyError, match="no such name"):
        system.tasks["gyro"]
    with pytest.raises(rtpipe.InputError, match=r"system.tasks\['p1'\].period is NaN"):
        system.tasks["p1"].period = float("nan")


# --- pickling -------------------------------------------------------------------


SPECS = ["paper-table3.toml", "cleanflight.toml", "work-queues.toml"]


def analyze_system(system):
    return without_clock(system.analyze())


def test_a_system_pickles_with_its_edits():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    system.tasks["p2"].period = "80ms"
    copy = pickle.loads(pickle.dumps(system))
    assert copy.to_toml() == system.to_toml() and copy.tasks == system.tasks
    assert analyze_system(copy) == analyze_system(system)


def test_a_pool_of_two_processes_analyses_systems_as_in_process():
    systems = [rtpipe.load(EXAMPLES / name) for name in SPECS]
    systems.append(rtpipe.waters(seed=3, tasks=20))
    here = [analyze_system(s) for s in systems]
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        there = pool.map(analyze_system, systems)
    assert there == here
