"""The typed results: every field of every report a documented property
of its class (rtpipe.reports, generated from the Rust structs), the dict
exactly ``--json``'s, the tables those ``--format csv`` prints as numpy
columns and DataFrames, and the exceptions with their attributes."""

import csv
import inspect
import io
import json
import subprocess
import sys

import numpy as np
import pytest

import rtpipe
from rtpipe import reports
from rtpipe._record import Record
from test_rtpipe import BIN, EXAMPLES

# The dict methods and keywords the generator suffixes with "_"
# (crates/cli/tests/python_reports.rs, `attribute`).
TAKEN = {"keys", "values", "items", "get", "pop", "copy", "update", "clear", "setdefault",
         "fromkeys", "popitem", "to_dict", "from", "class", "def", "tables"}


def attribute(key):
    return key + "_" if key in TAKEN else key


def every_field_is_a_documented_property(obj, at="report"):
    """Walks the report: each key a property of the object's class, with a
    docstring, that returns the value (wrapped where it is an object)."""
    for key, value in obj.items():
        if key in ("exit_status", "samples", "spec"):
            continue  # Python's own, on the Report base
        prop = getattr(type(obj), attribute(key), None)
        assert isinstance(prop, property), f"{at}.{key}: no property on {type(obj).__name__}"
        assert prop.__doc__, f"{at}.{key} has no docstring"
        got = getattr(obj, attribute(key))
        assert got == value, f"{at}.{key}"
        items = got if isinstance(got, list) else list(got.values()) if (
            isinstance(got, dict) and not isinstance(got, Record)) else [got]
        for i, item in enumerate(items):
            if isinstance(item, Record):
                every_field_is_a_documented_property(item, f"{at}.{key}[{i}]")
            elif isinstance(item, dict):
                pytest.fail(f"{at}.{key}[{i}] is a plain dict: its class is missing")


@pytest.fixture(scope="module")
def table3():
    return rtpipe.load(EXAMPLES / "paper-table3.toml")


def test_each_command_returns_its_class_and_every_field_is_a_property(table3):
    analysis = table3.analyze(margins=True, all_paths=True)
    assert type(analysis) is reports.AnalysisReport
    every_field_is_a_documented_property(analysis)
    sim = table3.simulate(outputs=200, phasing="search", search_steps=2)
    assert type(sim) is reports.SimulationReport
    every_field_is_a_documented_property(sim)
    triggered = rtpipe.load(EXAMPLES / "work-queues.toml").simulate(outputs=100)
    every_field_is_a_documented_property(triggered)
    flight = rtpipe.load(EXAMPLES / "cleanflight.toml").fly(duration="2s")
    assert type(flight) is reports.FlightReport
    every_field_is_a_documented_property(flight)
    design = rtpipe.load(EXAMPLES / "cleanflight-design.toml").design(margins=True)
    assert type(design) is reports.DesignReport
    every_field_is_a_documented_property(design)
    assert isinstance(design.spec, rtpipe.System)


def test_a_run_returns_its_report_typed():
    # The best-effort class runs anywhere, root or not.
    r = rtpipe.load(EXAMPLES / "paper-table3.toml").run(
        duration="300ms", policy="other", best_effort=True
    )
    assert type(r) is reports.RunReport and r.run.policy == r["run"]["policy"]
    every_field_is_a_documented_property(r)


def test_a_campaign_returns_its_summary_or_its_plan(tmp_path):
    from test_campaign import small_config

    config = small_config(tmp_path, systems=20, shard_size=10)
    plan = rtpipe.campaign(config, tmp_path / "out", plan=True)
    assert type(plan) is reports.CampaignPlan and plan.shards == 2
    every_field_is_a_documented_property(plan)
    summary = rtpipe.campaign(config, tmp_path / "out", jobs=1)
    assert type(summary) is reports.CampaignSummary and summary.written == 2
    every_field_is_a_documented_property(summary)
    assert list(summary.tables) and all(t.rows for t in summary.tables.values())


def test_attributes_read_the_report_and_the_dict_stays_the_json(table3):
    r = table3.analyze()
    chain = r.chains[0]
    assert isinstance(chain, reports.Chain)
    assert chain.sound == r["chains"][0]["sound"]
    assert chain.from_event.sound == r["chains"][0]["from_event"]["sound"]
    assert r.schedulability.cpus[0].utilization == r["schedulability"]["cpus"][0]["utilization"]
    assert r.tasks[0].name == "p1" and r.exit_status == 0
    plain = r.to_dict()
    assert type(plain) is dict and type(plain["chains"][0]) is dict
    assert json.loads(json.dumps(r)) == plain
    # Item access is the plain JSON, as before results were typed.
    assert type(r["chains"][0]) is dict


def csv_tables(command, spec, *flags):
    """`--format csv`'s tables: {name: (header, rows)}."""
    if not BIN.exists():
        pytest.skip(f"no rtpipe binary at {BIN}")
    out = subprocess.run([str(BIN), command, str(spec), *flags, "--format", "csv"],
                         capture_output=True, text=True, check=False).stdout
    tables = {}
    for block in out.strip().split("\n\n"):
        lines = block.splitlines()
        name = lines[0][2:] if lines[0].startswith("# ") else None
        body = list(csv.reader(io.StringIO("\n".join(lines[1:] if name else lines))))
        tables[name] = (body[0], body[1:])
    return tables


def test_the_tables_are_those_of_format_csv(table3):
    r = table3.analyze()
    want = csv_tables("analyze", EXAMPLES / "paper-table3.toml")
    assert list(r.tables) == list(want)
    for name, (header, rows) in want.items():
        t = r.tables[name]
        assert list(t) == header and t.rows == len(rows)
        for col, cells in zip(header, zip(*rows)):
            got = ["" if v is None else v for v in t[col].tolist()]
            for g, c in zip(got, cells):
                if isinstance(g, float):
                    assert (c == "" and np.isnan(g)) or g == pytest.approx(float(c)), (name, col)
                elif isinstance(g, bool):
                    assert str(g).lower() == c, (name, col)
                else:
                    assert str(g) == c, (name, col)


def test_tables_become_frames_without_copying_numbers(table3):
    pd = pytest.importorskip("pandas")
    pl = pytest.importorskip("polars")
    pa = pytest.importorskip("pyarrow")
    r = table3.analyze()
    chains = r.to_pandas("chains")
    assert isinstance(chains, pd.DataFrame) and list(chains.columns) == list(r.tables["chains"])
    assert chains["sound"].tolist() == [c.sound for c in r.chains]
    assert isinstance(r.to_polars("tasks"), pl.DataFrame)
    assert isinstance(r.to_arrow("tasks"), pa.Table)
    column = r.tables["tasks"]["utilization"]
    assert not column.flags.writeable and column.base is not None  # a view of rtpipe's buffer
    with pytest.raises(KeyError, match="it has"):
        r.table("nope")


def test_samples_are_a_table_with_nulls_where_the_run_ended(table3):
    pd = pytest.importorskip("pandas")
    pl = pytest.importorskip("polars")
    run = table3.simulate(outputs=100, samples=True)
    assert run.samples is not None and run["samples"] is run.samples
    frame = run.samples.to_pandas()
    assert str(frame["reaction_ns"].dtype) == "Int64"
    assert frame["reaction_ns"].isna().sum() == np.ma.count_masked(run.samples["reaction_ns"])
    assert run.to_polars("samples")["reaction_ns"].null_count() == frame["reaction_ns"].isna().sum()
    assert isinstance(run.to_dict()["samples"], dict)


def test_a_missing_frame_library_names_its_pip_package(table3, monkeypatch):
    r = table3.analyze()
    for package in ("pandas", "polars", "pyarrow"):
        monkeypatch.setitem(sys.modules, package, None)
        with pytest.raises(ImportError, match=f"pip install {package}"):
            getattr(r, "to_" + ("arrow" if package == "pyarrow" else package))("chains")
        monkeypatch.undo()


def test_a_spec_error_carries_its_first_place_key_and_fix():
    text = "[system]\nname = \"x\"\n[tasks.a]\nperiod = -3\nexec = 1\n"
    with pytest.raises(rtpipe.SpecError) as e:
        rtpipe.load(text, name="bad.toml")
    err = e.value
    assert (err.file, err.line, err.column, err.key) == ("bad.toml", 4, 10, "tasks.a.period")
    assert err.fix == "give period a value greater than zero"
    assert err.diagnostics[0]["key"] == "tasks.a.period"
    assert isinstance(err, rtpipe.RtpipeError)


def test_an_input_error_names_the_argument_at_fault(table3):
    with pytest.raises(rtpipe.InputError) as e:
        table3.simulate(seed=-1)
    assert e.value.argument == "seed" and e.value.help
    with pytest.raises(rtpipe.InputError) as e:
        table3.analyze(mode="loose")
    assert e.value.argument == "mode"


def test_every_declared_attribute_reads_on_every_error():
    with pytest.raises(rtpipe.InputError) as e:
        rtpipe.load({"system": {"name": "x"}, "tasks": {"a": {"period": float("nan")}}})
    assert e.value.argument is None and "NaN" in str(e.value)


def test_the_exception_hierarchy():
    assert issubclass(rtpipe.SpecError, rtpipe.RtpipeError)
    assert issubclass(rtpipe.InputError, rtpipe.RtpipeError)
    # A run that could not start is bad input too (code that caught
    # InputError before RunError existed still does).
    assert issubclass(rtpipe.RunError, rtpipe.InputError)
    assert issubclass(rtpipe.InternalError, rtpipe.RtpipeError)


def test_a_run_that_cannot_start_raises_run_error():
    # A CPU this machine does not have: refused before any thread starts.
    text = (EXAMPLES / "paper-table3.toml").read_text()
    system = rtpipe.load(text.replace("[tasks.p1]", "[tasks.p1]\ncpu = 1000", 1), name="far.toml")
    with pytest.raises(rtpipe.RunError) as e:
        system.run(duration="100ms", policy="other", best_effort=True)
    assert e.value.help


def test_help_explains_every_argument():
    methods = [getattr(rtpipe.System, c) for c in ("analyze", "simulate", "fly", "run", "design")]
    for f in methods + [rtpipe.campaign, rtpipe.waters]:
        doc = inspect.getdoc(f)
        section = doc.split("\nArguments:\n", 1)[1]
        for key in inspect.signature(f).parameters:
            if key != "self":
                assert f"\n    {key}: " in "\n" + section, f"{f.__qualname__}: {key}"
                flag = "--" + key.replace("_", "-") + " "
                assert flag not in section, f"{f.__qualname__} names {flag}, not {key}"
