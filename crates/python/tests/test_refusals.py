"""Every refusal of the command line's flags is a refusal from Python too,
said in Python's terms: the same checks (the option structs' own
validation, run by both), the same message, naming the keyword argument
(``search_steps``) where the command line names its flag
(``--search-steps``)."""

import re
import subprocess

import pytest

import rtpipe
from test_rtpipe import BIN, EXAMPLES


def in_python_terms(line):
    """A command-line message with each flag named as its keyword."""
    return re.sub(
        r"--([a-z][a-z-]*)(?:[ =]<[^>]*>)?", lambda m: m.group(1).replace("-", "_"), line
    )


def refused_by_binary(command, spec, flags):
    """The command line's first error line (without `error: `); it must
    exit 2 (bad input)."""
    if not BIN.exists():
        pytest.skip(f"no rtpipe binary at {BIN} (cargo build --release, or set RTPIPE_BIN)")
    out = subprocess.run(
        [str(BIN), command, str(spec), *flags, "--json"], capture_output=True, text=True,
        check=False,
    )
    assert out.returncode == 2, out.stderr
    first = next(l for l in out.stderr.splitlines() if l.startswith("error: "))
    return first[len("error: "):]


@pytest.mark.parametrize(
    "command,file,kwargs,flags",
    [
        # A flag that would do nothing.
        ("simulate", "paper-table3.toml", {"search_steps": 3}, ["--search-steps", "3"]),
        ("simulate", "paper-table3.toml", {"seed": 1}, ["--seed", "1"]),
        ("simulate", "paper-table3.toml", {"window": "0,10"}, ["--window", "0,10"]),
        ("fly", "cleanflight.toml", {"sweep": True, "log": "f.csv"},
         ["--sweep", "--log", "f.csv"]),
        ("fly", "cleanflight.toml", {"mission": "steps,gusty"}, ["--mission", "steps,gusty"]),
        # fly --sweep: the flags of how a timing is flown, judged and
        # checked, refused as the command line refuses them.
        ("fly", "cleanflight.toml", {"check_step": 0.02}, ["--check-step", "0.02"]),
        ("fly", "cleanflight.toml", {"sweep": True, "check_step": 0.6},
         ["--sweep", "--check-step", "0.6"]),
        ("fly", "cleanflight.toml", {"sweep": True, "check_step": -0.02},
         ["--sweep", "--check-step=-0.02"]),
        ("fly", "cleanflight.toml", {"sweep": True, "seeds": 0}, ["--sweep", "--seeds", "0"]),
        ("fly", "cleanflight.toml", {"sweep": True, "phases": 101},
         ["--sweep", "--phases", "101"]),
        ("fly", "cleanflight.toml", {"sweep": True, "pass_rate": 1.5},
         ["--sweep", "--pass-rate", "1.5"]),
        ("fly", "cleanflight.toml", {"sweep": True, "confidence": 0.9},
         ["--sweep", "--confidence", "0.9"]),
        ("fly", "cleanflight.toml", {"sweep": True, "pass_rate": 0.9, "confidence": 1},
         ["--sweep", "--pass-rate", "0.9", "--confidence", "1"]),
        ("fly", "cleanflight.toml", {"sweep": True, "resolution": 0.7},
         ["--sweep", "--resolution", "0.7"]),
        ("fly", "cleanflight.toml", {"sweep": True, "safety": 0}, ["--sweep", "--safety", "0"]),
        ("design", "cleanflight-design.toml", {"seed": 3}, ["--seed", "3"]),
        ("design", "cleanflight-design.toml", {"flights": 5, "vehicle": "racer5"},
         ["--flights", "5", "--vehicle", "racer5"]),
        # design: every check of its flags alone (DesignArgs::validate).
        ("design", "cleanflight-design.toml", {"method": "boxes", "solver": "microlp"},
         ["--method", "boxes", "--solver", "microlp"]),
        ("design", "cleanflight-design.toml", {"pass_rate": 0.9}, ["--pass-rate", "0.9"]),
        ("design", "cleanflight-design.toml", {"confidence": 0.9}, ["--confidence", "0.9"]),
        ("design", "cleanflight-design.toml", {"fly": "steps", "flights": 5},
         ["--fly", "steps", "--flights", "5"]),
        ("design", "cleanflight-design.toml", {"fly": "steps", "pass_rate": 0.99, "flights": 100},
         ["--fly", "steps", "--pass-rate", "0.99", "--flights", "100"]),
        ("design", "cleanflight-design.toml", {"max_utilization": 0.8},
         ["--max-utilization", "0.8"]),
        ("design", "cleanflight-design.toml", {"objective": "margin"},
         ["--objective", "margin"]),
        ("design", "cleanflight-design.toml",
         {"objective": "margin", "max_utilization": 0.8, "fly": "steps"},
         ["--objective", "margin", "--max-utilization", "0.8", "--fly", "steps"]),
        ("design", "cleanflight-design.toml", {"overwrite_spec": True}, ["--overwrite-spec"]),
        ("design", "cleanflight-design.toml", {"time_limit": -1}, ["--time-limit=-1"]),
        ("design", "cleanflight-design.toml", {"time_limit": 2e6}, ["--time-limit", "2000000.0"]),
        ("design", "cleanflight-design.toml", {"fly": "steps", "pass_rate": 1.5},
         ["--fly", "steps", "--pass-rate", "1.5"]),
        ("design", "cleanflight-design.toml", {"fly": "steps", "flights": 0},
         ["--fly", "steps", "--flights", "0"]),
        ("design", "cleanflight-design.toml", {"max_utilization": 0}, ["--max-utilization", "0"]),
        ("design", "cleanflight-design.toml", {"method": "exact"}, ["--method", "exact"]),
        ("design", "cleanflight-design.toml", {"objective": "speed"}, ["--objective", "speed"]),
        ("design", "cleanflight-design.toml", {"mode": "loose"}, ["--mode", "loose"]),
        # run: every check of its flags alone (RunArgs::validate), refused
        # before anything runs, so without root too.
        ("run", "paper-table3.toml", {"policy": "other"}, ["--policy", "other"]),
        ("run", "paper-table3.toml", {"best_effort": True}, ["--best-effort"]),
        ("run", "paper-table3.toml", {"policy": "fifo", "best_effort": True},
         ["--policy", "fifo", "--best-effort"]),
        ("run", "paper-table3.toml", {"load": 65}, ["--load", "65"]),
        ("run", "paper-table3.toml", {"synthetic": True, "vehicle": "racer5"},
         ["--synthetic", "--vehicle", "racer5"]),
        ("run", "paper-table3.toml", {"duration": "0s"}, ["--duration", "0s"]),
        ("run", "paper-table3.toml", {"duration": "-1"}, ["--duration", "-1"]),
        ("run", "paper-table3.toml", {"duration": "soon"}, ["--duration", "soon"]),
        ("run", "paper-table3.toml", {"policy": "rr"}, ["--policy", "rr"]),
        ("run", "paper-table3.toml", {"load": -1}, ["--load=-1"]),
        # run: what needs the spec too (no flight body to fly).
        ("run", "paper-table3.toml", {"mission": "hover"}, ["--mission", "hover"]),
        # A value the parser refuses.
        ("simulate", "paper-table3.toml", {"seed": -1}, ["--seed=-1"]),
        ("simulate", "paper-table3.toml", {"outputs": 0}, ["--outputs", "0"]),
        ("simulate", "paper-table3.toml", {"exec": "often"}, ["--exec", "often"]),
        ("analyze", "paper-table3.toml", {"mode": "loose"}, ["--mode", "loose"]),
    ],
)
def test_every_refusal_of_the_binary_raises_from_python_naming_the_keyword(
    command, file, kwargs, flags
):
    spec = EXAMPLES / file
    expected = refused_by_binary(command, spec, flags)
    with pytest.raises(rtpipe.InputError) as e:
        getattr(rtpipe.load(spec), command)(**kwargs)
    said = str(e.value).splitlines()[0]
    # The same message (the values a flag takes may follow it).
    assert said.startswith("error: " + in_python_terms(expected)), said
    assert "--" not in str(e.value), str(e.value)
    for key in kwargs:
        if "--" + key.replace("_", "-") in expected:
            assert key in said


def test_a_negative_seed_is_a_bad_value_not_an_unexpected_argument():
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    with pytest.raises(rtpipe.InputError) as e:
        system.simulate(seed=-1, phasing="random")
    text = str(e.value)
    assert "invalid value '-1' for 'seed'" in text, text
    assert "unexpected argument" not in text and "-- -1" not in text, text


@pytest.mark.parametrize("value", [0, 1, "yes", 1.0])
def test_a_switch_takes_a_bool_only(value):
    system = rtpipe.load(EXAMPLES / "paper-table3.toml")
    with pytest.raises(TypeError, match=r"all_paths=.*: give True or False") as e:
        system.analyze(all_paths=value)
    assert "unexpected argument" not in str(e.value)
