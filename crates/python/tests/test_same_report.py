"""One report, two front ends: on every command, the dict Python returns
is the JSON the binary prints for the same inputs (wall-clock figures
aside; a real run's measurements differ run to run, so of `run` the shape
and the spec's part are compared)."""

import json
import subprocess

import pytest

import rtpipe
from test_campaign import small_config
from test_rtpipe import BIN, EXAMPLES

CLOCK = ("seconds", "real_time", "per_second")


def without_clock(v):
    if isinstance(v, dict):
        return {k: without_clock(x) for k, x in v.items() if not any(c in k for c in CLOCK)}
    if isinstance(v, list):
        return [without_clock(x) for x in v]
    return v


def binary(*args):
    """The command line's --json report and exit status."""
    if not BIN.exists():
        pytest.skip(f"no rtpipe binary at {BIN} (cargo build --release, or set RTPIPE_BIN)")
    out = subprocess.run([str(BIN), *map(str, args), "--json"], capture_output=True, check=False)
    assert out.stdout, out.stderr
    return json.loads(out.stdout), out.returncode


@pytest.mark.parametrize(
    "command,file,kwargs,flags",
    [
        ("analyze", "paper-table3.toml", {"all_paths": True, "margins": True},
         ["--all-paths", "--margins"]),
        ("analyze", "work-queues.toml", {"mode": "paper"}, ["--mode", "paper"]),
        ("simulate", "paper-table3.toml",
         {"outputs": 20, "phasing": "search", "search_steps": 2, "seed": 3},
         ["--outputs", "20", "--phasing", "search", "--search-steps", "2", "--seed", "3"]),
        ("simulate", "work-queues.toml", {"duration": "200ms"}, ["--duration", "200ms"]),
        ("fly", "cleanflight.toml", {"mission": "hover", "duration": "3s", "seed": 1},
         ["--mission", "hover", "--duration", "3s", "--seed", "1"]),
        ("fly", "cleanflight.toml",
         {"sweep": True, "scale": "1..2", "per_octave": 1, "mission": "hover", "duration": "4s"},
         ["--sweep", "--scale", "1..2", "--per-octave", "1", "--mission", "hover",
          "--duration", "4s"]),
        # How a timing is flown, judged and checked below its limit.
        ("fly", "cleanflight.toml",
         {"sweep": True, "scale": "1..2", "per_octave": 1, "mission": "hover", "duration": "4s",
          "seeds": 2, "phases": 2, "pass_rate": 0.5, "confidence": 0.6, "resolution": 0.1,
          "check_step": 0.1, "safety": 0.9},
         ["--sweep", "--scale", "1..2", "--per-octave", "1", "--mission", "hover",
          "--duration", "4s", "--seeds", "2", "--phases", "2", "--pass-rate", "0.5",
          "--confidence", "0.6", "--resolution", "0.1", "--check-step", "0.1",
          "--safety", "0.9"]),
        ("design", "table2-design.toml", {"mode": "paper"}, ["--mode", "paper"]),
    ],
)
def test_python_returns_the_binarys_report(command, file, kwargs, flags):
    spec = EXAMPLES / file
    got = getattr(rtpipe.load(spec), command)(**kwargs)
    got.pop("spec", None)
    expected, status = binary(command, spec, *flags)
    assert got.pop("exit_status") == status
    assert without_clock(got) == without_clock(expected)
    assert list(got) == list(expected)  # the same keys in the same order


def test_a_campaign_and_its_plan_are_the_binarys_reports(tmp_path):
    config = small_config(tmp_path, systems=10, shard_size=5)
    for plan in (True, False):
        out = tmp_path / f"out-{plan}"
        flags = ["--plan"] if plan else []
        got = rtpipe.campaign(config, out, plan=plan, jobs=1)
        expected, status = binary("campaign", config, tmp_path / f"out-{plan}-cli",
                                  "--jobs", "1", *flags)
        assert got.pop("exit_status") == status == 0
        # The directories differ by name only.
        got["out"] = expected["out"]
        assert without_clock(got) == without_clock(expected)


def test_a_run_from_python_is_the_binarys_report():
    spec = EXAMPLES / "paper-table3.toml"
    kwargs = {"duration": "100ms", "policy": "other", "best_effort": True}
    got = rtpipe.load(spec).run(**kwargs)
    expected, status = binary("run", spec, "--duration", "100ms", "--policy", "other",
                              "--best-effort")
    assert list(got)[:-1] == list(expected)  # exit_status last
    assert got["run"]["policy"] == expected["run"]["policy"] == "other"
    assert got["run"]["real_time"] is expected["run"]["real_time"] is False
    assert [t["name"] for t in got["tasks"]] == [t["name"] for t in expected["tasks"]]
    # The analysis' part is the same: only the measurements differ.
    for g, e in zip(got["tasks"], expected["tasks"]):
        assert {k: v for k, v in g.items() if k != "observed"} == {
            k: v for k, v in e.items() if k != "observed"
        }
    assert got["exit_status"] in (0, 1)


def test_a_real_time_run_needs_root_or_says_so():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    try:
        got = system.run(duration="100ms")
    except rtpipe.InputError as e:
        # Without CAP_SYS_NICE the kernel refuses SCHED_FIFO: bad input, said.
        assert "SCHED_FIFO" in str(e) or "privilege" in str(e) or "permission" in str(e), str(e)
        pytest.skip(f"no real-time scheduling here: {e}")
    assert got["run"]["policy"] == "fifo" and got["run"]["real_time"] is True


def test_run_flags_are_refused_in_python_terms():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    with pytest.raises(rtpipe.InputError) as e:
        system.run(policy="other")
    assert "best_effort" in str(e.value) and "--" not in str(e.value), str(e.value)
    with pytest.raises(rtpipe.InputError) as e:
        system.run(vehicle="racer5", policy="other", best_effort=True)
    assert "vehicle" in str(e.value) and "--vehicle" not in str(e.value), str(e.value)


def test_python_keeps_its_ctrl_c_after_a_run():
    # The runtime catches the stop signals while its threads run; Python's
    # handler is back after it, so Ctrl-C still stops a later long call.
    import os
    import signal
    import threading

    signal.signal(signal.SIGINT, signal.default_int_handler)
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    system.run(duration="50ms", policy="other", best_effort=True)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        system.simulate(duration="5000000s")
