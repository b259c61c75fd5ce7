"""Nothing a Python caller passes kills the interpreter, and Ctrl-C stops
the work itself, not only the wait for it. Each probe that could crash runs
in a fresh interpreter: a crash there is a signal in its return code, not a
lost test run."""

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

import rtpipe

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"


def probe(code):
    """Runs `code` (after `import rtpipe`) in a fresh interpreter; it
    prints the name of the exception it raised and its message. Returns
    (exception name, message); fails on a crash (a signal)."""
    script = "import rtpipe\n" + textwrap.dedent(code)
    wrapped = (
        "try:\n"
        + textwrap.indent(script, "    ")
        + "\nexcept BaseException as e:\n"
        "    print(type(e).__name__)\n"
        "    print(e)\n"
        "else:\n"
        "    print('no exception')\n"
    )
    r = subprocess.run(
        [sys.executable, "-c", wrapped], capture_output=True, text=True, timeout=600,
        cwd=ROOT,
    )
    assert r.returncode == 0, f"exit {r.returncode} (a negative one is a signal): {r.stderr}"
    name, _, message = r.stdout.partition("\n")
    return name, message.strip()


SPEC = 'd = {"system": {"name": "x"}, "tasks": {"a": {"period": "10ms", "exec": "1ms"}}}\n'


@pytest.mark.parametrize(
    "build,place,says",
    [
        ('d["system"]["loop"] = d', "spec.system.loop", "contains itself"),
        ('d["tasks"]["a"]["l"] = [1]; d["tasks"]["a"]["l"].append(d["tasks"]["a"]["l"])',
         "spec.tasks.a.l[1]", "contains itself"),
        ("x = []\nfor _ in range(10000):\n    x = [x]\nd['system']['deep'] = x",
         "spec.system.deep", "nests deeper than 64 levels"),
        ("y = {}\nfor _ in range(10000):\n    y = {'k': y}\nd['system']['deep'] = y",
         "spec.system.deep", "nests deeper than 64 levels"),
    ],
)
def test_cycles_and_deep_nesting_are_refused_with_their_key_path(build, place, says):
    name, message = probe(SPEC + build + "\nrtpipe.load(d)\n")
    assert name == "InputError", message
    assert place in message and says in message, message


@pytest.mark.parametrize(
    "value,kind",
    [
        ("itertools.count()", "count"),
        ("(i for i in itertools.count())", "generator"),
        ("iter([1, 2])", "list_iterator"),
        ("object()", "object"),
        ("{1, 2}", "set"),
        ("b'10ms'", "bytes"),
    ],
)
def test_values_that_are_not_plain_data_are_refused_naming_key_and_types(value, kind):
    code = "import itertools\n" + SPEC + f"d['tasks']['a']['exec'] = {value}\nrtpipe.load(d)\n"
    name, message = probe(code)
    assert name == "InputError", message
    assert message.startswith(f"spec.tasks.a.exec is a {kind}"), message
    assert "str, int, float, bool, list, tuple or dict" in message, message


@pytest.mark.parametrize("value,shown", [("nan", "NaN"), ("inf", "inf"), ("-inf", "-inf")])
def test_non_finite_numbers_are_refused_naming_their_key(value, shown):
    code = SPEC + f"d['tasks']['a']['period'] = float('{value}')\nrtpipe.load(d)\n"
    name, message = probe(code)
    assert name == "InputError", message
    assert f"spec.tasks.a.period is {shown}" in message and "finite" in message, message


def test_plain_data_still_loads_and_tuples_are_lists():
    with pytest.raises(rtpipe.InputError, match=r"spec\.tasks\.a\.big is an integer outside"):
        rtpipe._rtpipe.dict_to_toml({"tasks": {"a": {"big": 2**70}}})
    assert rtpipe._rtpipe.dict_to_toml({"a": (1, 2.5, "x", True)}) == 'a = [1, 2.5, "x", true]\n'
    shared = {"period": "10ms", "exec": "1ms"}
    # The same dict twice is not a cycle.
    system = rtpipe.load({"system": {"name": "x"}, "tasks": {"a": shared, "b": dict(shared)}})
    assert system.tasks == ["a", "b"]


def test_too_many_samples_raise_memory_error_naming_the_file_option():
    code = """
    s = rtpipe.load("examples/cleanflight.toml")
    rtpipe._rtpipe.run("fly", s._spec, ["--duration", "60s"], True, 1000)
    """
    name, message = probe(code)
    assert name == "MemoryError", message
    assert "more than 1000 sample rows" in message and 'samples="FILE.csv"' in message
    assert rtpipe.MAX_SAMPLE_ROWS == rtpipe._rtpipe.MAX_SAMPLE_ROWS >= 1_000_000


def test_samples_stream_to_a_file_given_as_the_samples_path(tmp_path):
    system = rtpipe.load(EXAMPLES / "cleanflight.toml")
    out = tmp_path / "rows.csv"
    held = system.fly(duration="3s", samples=True)["samples"]
    streamed = system.fly(duration="3s", samples=out)
    assert "samples" not in streamed
    lines = out.read_text().splitlines()
    assert lines[0].startswith("chain,sample,read_ns")
    assert len(lines) - 1 == len(held["read_ns"]) > 1000
    with pytest.raises(TypeError, match="samples=3"):
        system.fly(samples=3)


def interrupt_after(seconds):
    """Sends this process SIGINT (Ctrl-C) after `seconds`."""
    signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def assert_idle():
    """No work runs on behind the call that returned (this process burns
    no CPU while it sleeps)."""
    time.sleep(0.1)
    cpu = time.process_time()
    time.sleep(0.5)
    assert time.process_time() - cpu < 0.1


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT")
@pytest.mark.parametrize(
    "kwargs",
    [
        dict(mission="hover", duration="100000s"),  # about a quarter of an hour
        dict(sweep=True, per_octave=12),  # hundreds of flights
    ],
)
def test_ctrl_c_stops_a_flight_before_the_call_returns(kwargs):
    system = rtpipe.load(EXAMPLES / "cleanflight.toml")
    interrupt_after(0.3)
    with pytest.raises(KeyboardInterrupt):
        system.fly(**kwargs)
    assert_idle()
    assert "flight" in system.fly(mission="hover", duration="2s")  # still works


def campaign_config(tmp_path):
    text = (ROOT / "examples" / "campaigns" / "waters.toml").read_text()
    text = text.replace("systems = 2000", "systems = 4000").replace(
        "shard_size = 500", "shard_size = 10"
    )
    path = tmp_path / "c.toml"
    path.write_text(text)
    return path


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT")
def test_ctrl_c_stops_a_campaigns_workers_before_the_call_returns(tmp_path):
    out = tmp_path / "out"
    interrupt_after(1.0)
    with pytest.raises(KeyboardInterrupt):
        rtpipe.campaign(campaign_config(tmp_path), out, jobs=2)
    written = sorted(p.name for p in out.iterdir())
    assert_idle()
    assert sorted(p.name for p in out.iterdir()) == written


@pytest.mark.parametrize(
    "shard", [(0, 2, 3), (2, 2), (-1, 2), (0, 0), ("0", "2"), (True, 2), (0.0, 2), [0, 2], 1]
)
def test_a_bad_shard_is_a_value_error_naming_the_argument(tmp_path, shard):
    with pytest.raises(ValueError, match=r"campaign\(shard=.*2-tuple \(index, count\)"):
        rtpipe.campaign(campaign_config(tmp_path), tmp_path / "out", shard=shard)
    assert not (tmp_path / "out").exists()


def test_a_good_shard_tuple_takes_any_integers(tmp_path):
    import numpy as np

    config = campaign_config(tmp_path)
    plan = rtpipe.campaign(config, tmp_path / "out", shard=(np.int64(1), 4), plan=True)
    # 400 shards of which part 1/4 owns every fourth: 100 (the plan gives
    # their count, not a list, so that 10^9 shards plan in bounded memory).
    assert plan["part"] == "1/4" and plan["part_shards"] == 100


def test_samples_none_is_no_samples():
    r = rtpipe.load(EXAMPLES / "paper-table3.toml").simulate(outputs=20, samples=None)
    assert "samples" not in r
