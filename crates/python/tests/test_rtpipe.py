"""The Python package against the command line it wraps: the same reports,
the same samples, errors with their places, the GIL free during long calls
and Ctrl-C honoured."""

import csv
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

import rtpipe

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"
BIN = Path(os.environ.get("RTPIPE_BIN", ROOT / "target" / "release" / "rtpipe"))
CLOCK_KEYS = ("seconds", "real_time")


def without_clock(v):
    """Wall-clock figures differ between two runs of the same command."""
    if isinstance(v, dict):
        return {k: without_clock(x) for k, x in v.items() if not any(c in k for c in CLOCK_KEYS)}
    if isinstance(v, list):
        return [without_clock(x) for x in v]
    return v


def binary(command, spec, *flags):
    """The command line's --json and exit status."""
    if not BIN.exists():
        pytest.skip(f"no rtpipe binary at {BIN} (cargo build --release, or set RTPIPE_BIN)")
    out = subprocess.run(
        [str(BIN), command, str(spec), *flags, "--json"], capture_output=True, check=False
    )
    return json.loads(out.stdout), out.returncode


def test_analyze_is_the_command_lines_json():
    spec = EXAMPLES / "paper-table3.toml"
    got = rtpipe.load(spec).analyze(all_paths=True)
    expected, status = binary("analyze", spec, "--all-paths")
    assert got.pop("exit_status") == status
    assert got == expected
    assert list(got) == list(expected)  # the same key order


def test_analyze_margins_is_the_command_lines_json(tmp_path):
    spec = EXAMPLES / "paper-table3.toml"
    out = tmp_path / "margins.csv"
    got = rtpipe.load(spec).analyze(margins=True, margins_csv=out)
    expected, status = binary("analyze", spec, "--margins")
    assert got.pop("exit_status") == status
    assert got == expected
    assert got["margins"]["exec"][0]["margin"] == 34.5
    assert out.read_text().startswith("kind,subject,key,")


def test_analyze_observed_is_the_command_lines_json(tmp_path):
    spec = EXAMPLES / "work-queues.toml"
    ages = tmp_path / "ages.csv"
    ages.write_text(
        "chain,topic,timestamp_ns,timestamp_sample_ns,data_age_ns\n"
        "rate loop,actuator_motors,1100000,1000000,100000\n"
        "rate loop,actuator_motors,2900000,1000000,1900000\n"
    )
    got = rtpipe.load(spec).analyze(observed=ages)
    expected, status = binary("analyze", spec, "--observed", str(ages))
    assert got.pop("exit_status") == status == 1
    assert got == expected
    measured = got["observed"]["measured"]
    assert [(m["metric"], m["count"], m["ok"]) for m in measured] == [
        ("reaction", 1, True),
        ("freshness", 2, False),
    ]
    assert measured[1]["worst_line"] == 3
    with pytest.raises(rtpipe.InputError, match=r"ages.csv:2:1: chain `yaw` is not in the spec"):
        ages.write_text("chain,topic,timestamp_ns,timestamp_sample_ns,data_age_ns\nyaw,t,2,1,1\n")
        rtpipe.load(spec).analyze(observed=ages)


@pytest.mark.parametrize(
    "command,file,kwargs,flags",
    [
        ("simulate", "paper-table3.toml", {"outputs": 50, "exec": "uniform", "seed": 7},
         ["--outputs", "50", "--exec", "uniform", "--seed", "7"]),
        ("simulate", "resources.toml", {"duration": "1s", "phasing": "random"},
         ["--duration", "1s", "--phasing", "random"]),
        ("fly", "cleanflight.toml", {"mission": "hover", "seed": 2},
         ["--mission", "hover", "--seed", "2"]),
        ("design", "cleanflight-design.toml", {}, []),
    ],
)
def test_commands_answer_what_the_binary_prints(command, file, kwargs, flags):
    spec = EXAMPLES / file
    got = getattr(rtpipe.load(spec), command)(**kwargs)
    got.pop("spec", None)
    expected, status = binary(command, spec, *flags)
    assert got.pop("exit_status") == status
    assert without_clock(got) == without_clock(expected)


def test_load_takes_a_path_text_or_a_dict():
    path = EXAMPLES / "paper-table2.toml"
    text = path.read_text()
    with open(path, "rb") as f:
        tables = tomllib.load(f)
    reports = [rtpipe.load(s).analyze() for s in (path, str(path), text, tables)]
    assert all(r == reports[0] for r in reports)
    system = rtpipe.load(tables)
    assert system.tasks == rtpipe.load(path).tasks
    assert "<dict>" in repr(system)


def test_samples_are_numpy_columns_equal_to_the_csv(tmp_path):
    spec = EXAMPLES / "paper-table3.toml"
    out = tmp_path / "s.csv"
    binary("simulate", spec, "--outputs", "60", "--samples", str(out))
    system = rtpipe.load(spec)
    cols = system.simulate(outputs=60, samples=True)["samples"]
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(cols["read_ns"]) > 100
    assert cols["read_ns"].dtype == np.int64 and cols["chain"].dtype == np.int32
    for i, row in enumerate(rows):
        assert system.chains[cols["chain"][i]] == row["chain"]
        assert cols["sample"][i] == int(row["sample"])
        for name in ("read_ns", "event_ns", "first_output_ns", "reaction_ns", "freshness_ns",
                     "event_reaction_ns", "event_freshness_ns"):
            value = cols[name][i]
            if row[name] == "":
                assert value is np.ma.masked, (name, i)
            else:
                assert int(value) == int(row[name]), (name, i)
    # Reaction is the first output less the read, wherever both exist.
    both = ~np.ma.getmaskarray(cols["reaction_ns"])
    assert both.sum() > 100
    assert np.array_equal(
        (cols["first_output_ns"] - cols["read_ns"])[both], cols["reaction_ns"][both]
    )


def test_a_flight_reports_its_quality_and_samples():
    r = rtpipe.load(EXAMPLES / "cleanflight.toml").fly(mission="hover", samples=True)
    assert r["flight"]["criteria_met"] is True and r["exit_status"] == 0
    assert r["flight"]["attitude_error_deg"]["rms"] < 1.0
    fresh = r["samples"]["freshness_ns"].compressed()
    assert len(fresh) > 1000 and fresh.min() > 0


def test_design_returns_the_designed_system():
    r = rtpipe.load(EXAMPLES / "cleanflight-design.toml").design()
    assert r["design"]["status"] == "optimal"
    designed = r["spec"]
    assert designed.free_tasks == []
    again = designed.analyze()
    assert again["ok"] is True
    assert again["schedulability"]["utilization"] == pytest.approx(r["design"]["objective"])


def test_design_for_margin_within_a_utilisation_cap():
    system = rtpipe.load(EXAMPLES / "timing-design.toml")
    r = system.design(objective="margin", max_utilization=0.6, margins=True)
    search = r["design"]["margin_search"]
    assert search["max_utilization"] == 0.6
    assert search["factor"] == pytest.approx(4 / 3, rel=2e-3)
    assert r["design"]["objective"] <= 0.6
    assert r["margins"]["scaling"][-1]["factor"] >= search["factor"]
    with pytest.raises(rtpipe.InputError, match="max_utilization"):
        system.design(objective="margin")


def test_a_bad_spec_raises_spec_error_with_its_place(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[system]\nname = "x"\n\n[tasks.a]\nperiod = "ten ms"\nexec = 1\n')
    with pytest.raises(rtpipe.SpecError) as e:
        rtpipe.load(bad)
    assert e.value.file == str(bad)
    (d,) = e.value.diagnostics
    assert d["line"] == 5 and d["column"] is not None
    assert "period" in str(e.value)
    with pytest.raises(rtpipe.SpecError):
        rtpipe.load("[system]\nname = 1\n")


def test_bad_arguments_raise_input_error_with_help():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    with pytest.raises(rtpipe.InputError) as e:
        system.simulate(exec="often")
    assert "often" in str(e.value) and e.value.help
    with pytest.raises(rtpipe.InputError) as e:
        system.simulate(duration="-3s")
    with pytest.raises(rtpipe.InputError, match="zeppelin"):
        rtpipe.load(EXAMPLES / "cleanflight.toml").fly(vehicle="zeppelin")
    with pytest.raises(rtpipe.InputError, match="None"):
        rtpipe.load({"system": {"name": None}})
    with pytest.raises(TypeError):
        rtpipe.load(42)
    free = rtpipe.load(EXAMPLES / "cleanflight-design.toml")
    for command in (free.analyze, free.simulate, free.fly):
        with pytest.raises(rtpipe.InputError, match="no fixed period for tasks") as e:
            command()
        assert "rtpipe design" in e.value.help
    assert issubclass(rtpipe.SpecError, rtpipe.RtpipeError)


def _ticks_during(work) -> tuple:
    """How often a Python thread that sleeps 1 ms between ticks ticked
    while ``work()`` ran in this thread, and how long it ran (s)."""
    ticks = 0
    done = threading.Event()

    def count():
        nonlocal ticks
        while not done.is_set():
            ticks += 1
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    start = time.monotonic()
    work()
    elapsed = time.monotonic() - start
    done.set()
    t.join()
    return ticks, elapsed


def test_the_gil_is_free_during_a_long_call():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    ticks, elapsed = _ticks_during(lambda: system.simulate(duration="50000s"))
    assert elapsed > 0.2, elapsed
    # The same thread beside a plain sleep (which frees the GIL), just
    # after: how fast it ticks on this machine now, whatever its load. A
    # call that held the GIL would let it tick only at the wrapper's 50 ms
    # polls (about 0.02 ticks per ms), far below a fifth of that rate.
    free, slept = _ticks_during(lambda: time.sleep(elapsed))
    assert ticks / elapsed > 0.2 * free / slept, (ticks, elapsed, free, slept)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT")
def test_ctrl_c_stops_a_long_call():
    # Python's own Ctrl-C handler, whatever an earlier test (Ray) left.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    start = time.monotonic()
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        system.simulate(duration="5000000s")
    # The full run takes about a minute; the interrupt ends it at once.
    assert time.monotonic() - start < 3.0
    # And the simulation stopped with it (no worker burning on behind).
    time.sleep(0.1)
    cpu = time.process_time()
    time.sleep(0.5)
    assert time.process_time() - cpu < 0.1
    # The package still works after it.
    assert system.analyze()["ok"] is True


def test_waters_is_the_generated_file(tmp_path):
    out = tmp_path / "w.toml"
    if not BIN.exists():
        pytest.skip("no rtpipe binary")
    subprocess.run([str(BIN), "generate", "waters", "--tasks", "24", "--seed", "5",
                    "--release", "synchronous", str(out)], check=True, capture_output=True)
    from_file = rtpipe.load(out)
    generated = rtpipe.waters(tasks=24, seed=5, release="synchronous")
    assert generated.to_toml() == from_file.to_toml()
    assert generated.analyze() == from_file.analyze()
    with pytest.raises(rtpipe.InputError, match="utilization"):
        rtpipe.waters(utilization=3)


def test_a_sweep_checks_below_its_limits_by_default_and_check_step_0_turns_it_off():
    """``fly(sweep=True)`` has the command line's default, ``check_step``
    0.02: check points on a ladder of 1.02^i; ``check_step=0`` none."""
    system = rtpipe.load(EXAMPLES / "cleanflight.toml")
    short = dict(sweep=True, scale="1..2", per_octave=1, mission="hover", duration="4s")

    def checks(**kwargs):
        report = system.fly(**short, **kwargs)
        return [p["value"] for p in report["points"] if p["stage"] == "check"]

    default = checks()
    assert default, "no check point by default"
    for x in default:
        i = math.log(x) / math.log(1.02)
        assert abs(i - round(i)) < 1e-6, f"{x} is not 1.02^i"
    assert checks(check_step=0) == []
