"""rtpipe from Python: the same analysis, simulator, design and flights as
the ``rtpipe`` command line, on the same crates.

>>> import rtpipe
>>> system = rtpipe.load("examples/paper-table3.toml")
>>> report = system.analyze()              # an rtpipe.reports.AnalysisReport
>>> report.chains[0].sound                 # a chain's sound bound, in the spec's unit
>>> report.to_pandas("chains")             # the chains table as a DataFrame
>>> run = system.simulate(outputs=1000, samples=True)
>>> run.samples["reaction_ns"]             # one numpy value per head sample

Every method returns a typed report (:mod:`rtpipe.reports`, generated
from the Rust report structs): a ``dict`` holding exactly what the
command's ``--json`` prints (the same keys, order and values; ``report["ok"]``
and ``report.to_dict()`` give them as before), plus ``exit_status``,
``samples`` (numpy columns) when asked for, and ``spec`` (a :class:`System`)
from :meth:`System.design`; each field is also a documented property, and
the report's tables (what ``--format csv`` prints) are under
``report.tables`` with ``to_pandas``, ``to_polars`` and ``to_arrow``.
Keyword arguments are the command's flags with
underscores (``search_steps=3`` is ``--search-steps 3``), and one left at
None takes the command line's default (``rtpipe COMMAND --help`` lists
them); the values are checked by the command line's own parser. Errors raise
:class:`SpecError` (with the first problem's ``file``, ``line``,
``column``, ``key`` and ``fix``, and every problem under ``diagnostics``),
:class:`InputError` (the argument at fault and ``help``), :class:`RunError`
(a run on this machine that could not start) or :class:`InternalError`
(a bug), all :class:`RtpipeError`. A run whose verdict fails (a limit
missed, a flight that crashed) still returns its report (``ok``,
``criteria_met`` say so), and the command line's exit status is its
``exit_status``.

Long calls release the GIL (other Python threads run meanwhile) and
Ctrl-C stops them with KeyboardInterrupt: the work itself stops (a
simulation, a flight, a design search, a campaign's workers) before the
call returns, and nothing it was writing is left behind.

Nothing passed from Python can crash the interpreter: a dict spec holds
plain data only (str, int, float, bool, list, tuple, dict: no iterators,
generators or other objects), without cycles, nested no deeper than a spec
file may be and with finite numbers; anything else raises
:class:`InputError` naming the key path.
"""

from __future__ import annotations

import inspect
import logging
import operator
import os
import re
import signal
import threading
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Type, TypeVar, Union

import numpy as np

from . import _rtpipe, reports
from ._record import Report, Table, table_from_raw
from ._rtpipe import InputError, InternalError, RtpipeError, RunError, SpecError
from .reports import (
    AnalysisReport,
    CampaignPlan,
    CampaignSummary,
    DesignReport,
    FlightReport,
    RunReport,
    SimulationReport,
    SweepReport,
)
from ._spec import Chain, Chains, Task, Tasks

__all__ = [
    "load",
    "waters",
    "import_e2eeval",
    "import_px4_ulog",
    "campaign",
    "System",
    "Task",
    "Chain",
    "RtpipeError",
    "SpecError",
    "InputError",
    "RunError",
    "InternalError",
    "Table",
    "reports",
    "AnalysisReport",
    "SimulationReport",
    "FlightReport",
    "SweepReport",
    "DesignReport",
    "RunReport",
    "CampaignSummary",
    "CampaignPlan",
    "MAX_SAMPLE_ROWS",
    "__version__",
]

__version__: str = _rtpipe.__version__

#: The most sample rows ``samples=True`` holds in memory (about 130 bytes
#: each while collected); a run with more stops there with MemoryError:
#: pass ``samples="FILE.csv"`` to stream any number to a file instead.
MAX_SAMPLE_ROWS: int = _rtpipe.MAX_SAMPLE_ROWS

log = logging.getLogger("rtpipe")

# Every attribute the stubs declare reads on every instance, None where a
# raise did not set it (an InputError about a dict spec names no keyword).
for _error, _attributes in (
    (InputError, ("argument", "help", "message")),
    (SpecError, ("file", "line", "column", "key", "message", "fix")),
):
    for _attribute in _attributes:
        setattr(_error, _attribute, None)
del _error, _attributes, _attribute

T = TypeVar("T")

Source = Union[str, "os.PathLike[str]", Mapping[str, Any]]


def load(source: Source, *, name: Optional[str] = None) -> "System":
    """Loads a system spec.

    ``source`` is a path to a spec file (TOML), TOML text (a ``str`` holding
    a newline), or a dict of the spec's tables (as ``tomllib.load`` gives
    them). ``name`` labels a text or dict spec in messages.
    """
    if isinstance(source, Mapping):
        text = _rtpipe.dict_to_toml(dict(source))
        return System(_rtpipe.load_text(text, name or "<dict>"))
    if isinstance(source, str) and "\n" in source:
        return System(_rtpipe.load_text(source, name or "<text>"))
    if isinstance(source, (str, os.PathLike)):
        return System(_rtpipe.load_path(os.fspath(source)))
    raise TypeError(
        f"load() takes a path, TOML text or a dict, not {type(source).__name__}"
    )


def waters(
    *,
    seed: Optional[int] = None,
    tasks: Optional[int] = None,
    utilization: Optional[float] = None,
    chains: Optional[int] = None,
    cpus: Optional[int] = None,
    release: Optional[str] = None,
) -> "System":
    """A WATERS 2015 task set with cause-effect chains, as ``rtpipe generate
    waters`` writes it (the same flags give the same system), without a
    file. ``release="synchronous"`` releases every task at 0."""
    options = dict(seed=seed, tasks=tasks, utilization=utilization, chains=chains,
                   cpus=cpus, release=release)
    keywords = list(options)
    return System(_speaking_python(keywords, lambda: _rtpipe.waters(_flags(options))))


def import_e2eeval(
    source: Union[str, "os.PathLike[str]"], *, name: Optional[str] = None
) -> Dict[str, "System"]:
    """The specs ``rtpipe import e2eeval FILE OUTDIR`` writes, without
    files: one :class:`System` per ECU (ECUs joined by a chain in one), by
    spec name. ``source`` is the path of E2EEvaluation's YAML or the YAML
    text itself (a ``str`` holding a newline), whose spec names come from
    ``name`` (default ``e2eeval.yaml``) as they come from a file's name.
    What the import notes (a task it had to change) is logged."""
    if isinstance(source, str) and "\n" in source:
        file, text = name or "e2eeval.yaml", source
    elif isinstance(source, (str, os.PathLike)):
        file, text = os.fspath(source), None
    else:
        raise TypeError(
            f"import_e2eeval() takes a path or YAML text, not {type(source).__name__}"
        )
    _, notes, specs, _ = _rtpipe.make("import e2eeval", [file, "<python>"], text)
    for note in notes:
        log.warning(note)
    return {spec_name: System(handle) for spec_name, handle in specs}


def import_px4_ulog(
    log_file: Union[str, "os.PathLike[str]"],
    *,
    exec: Optional[str] = None,
    exec_from: Union[str, "os.PathLike[str]", None] = None,
    exec_us: Optional[Mapping[str, int]] = None,
    px4_version: Optional[str] = None,
) -> Dict[str, Any]:
    """What ``rtpipe import px4-ulog LOG OUTDIR`` writes and prints, without
    files: ``"system"`` (the spec.toml, a :class:`System`), ``"observed"``
    (observed.csv's text: every logged data age, for
    :meth:`System.analyze`'s ``observed`` once written to a file),
    ``"board"``, ``"lockstep"``, ``"ages"`` (per chain and topic: messages,
    min_ns, max_ns) and ``"assumptions"``. ``exec`` ("max" or "mean"),
    ``exec_from`` (another log), ``exec_us`` (``{module: microseconds}``)
    and ``px4_version`` ("1.6") are the flags."""
    options = dict(exec=exec, exec_from=exec_from, px4_version=px4_version)
    flags = [os.fspath(log_file), "<python>"] + _flags(options)
    if exec_us is not None:
        if not isinstance(exec_us, Mapping):
            raise TypeError(f"exec_us={exec_us!r}: give a dict {{module: microseconds}}")
        flags += [f"--exec-us={module}={us}" for module, us in exec_us.items()]
    keywords = ["exec", "exec_from", "exec_us", "px4_version"]
    made = _speaking_python(keywords, lambda: _rtpipe.make("import px4-ulog", flags))
    report, _, specs, files = made
    return dict(system=System(specs[0][1]), observed=files["observed.csv"], **report)


def _flags(options: Mapping[str, Any], switches: Sequence[str] = ()) -> List[str]:
    """Keyword arguments as command-line flags: None and False leave a flag
    out, True gives a switch (one of ``switches``) bare, a list joins its
    items with commas. A value is always joined to its flag
    (``--seed=-1``), so that the parser reads it as that flag's value
    whatever it looks like, and refuses it naming the flag; a switch takes
    a bool only."""
    out = []
    for key, value in options.items():
        flag = "--" + key.replace("_", "-")
        if key in switches:
            if value is not None and not isinstance(value, (bool, np.bool_)):
                raise TypeError(f"{key}={value!r}: give True or False")
            if value:
                out.append(flag)
            continue
        if value is None:
            continue
        if isinstance(value, (list, tuple)):
            value = ",".join(str(v) for v in value)
        elif isinstance(value, os.PathLike):
            value = os.fspath(value)
        out.append(f"{flag}={value}")
    return out


def _switches(function: Any) -> Tuple[str, ...]:
    """The keywords of ``function`` that are switches (those whose default
    is False)."""
    params = inspect.signature(function).parameters.values()
    return tuple(p.name for p in params if p.default is False and p.name != "samples")


def _pythonic(message: str, keywords: Sequence[str]) -> str:
    """A message of the command line's parser or checks, with each flag
    that is one of ``keywords`` named as that keyword (``--search-steps``
    and ``'--search-steps <N>'`` are ``search_steps``)."""
    for key in sorted(keywords, key=len, reverse=True):
        flag = "--" + key.replace("_", "-")
        message = re.sub(re.escape(flag) + r"(=| )?<[^>]*>", key, message)
        message = re.sub(re.escape(flag) + r"(?![\w-])", key, message)
    return message


def _speaking_python(keywords: Sequence[str], call: Callable[[], T]) -> T:
    """``call()``, its InputError said in terms of ``keywords``."""
    try:
        return call()
    except InputError as e:
        text = _pythonic(str(e), keywords)
        err = type(e)(text)
        for attr in ("help", "message"):
            value = getattr(e, attr, None)
            setattr(err, attr, _pythonic(value, keywords) if isinstance(value, str) else value)
        err.argument = _argument_at_fault(text, keywords)
        raise err from None


def _argument_at_fault(message: str, keywords: Sequence[str]) -> Optional[str]:
    """The keyword argument a message names first (``'seed'``), or None
    when it names none (a file's content, the machine)."""
    found = [(m.start(), k) for k in keywords
             for m in [re.search(r"(?<![\w-])" + re.escape(k) + r"(?![\w-])", message)] if m]
    return min(found)[1] if found else None


_STOP_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)


def _signal_handlers() -> List[Tuple[int, Any]]:
    """The Python handlers of the stop signals (none off the main thread,
    where Python cannot set them)."""
    if threading.current_thread() is not threading.main_thread():
        return []
    return [(sig, signal.getsignal(sig)) for sig in _STOP_SIGNALS]


def _restore_signal_handlers(kept: List[Tuple[int, Any]]) -> None:
    for sig, handler in kept:
        if handler is not None:
            signal.signal(sig, handler)


def _columns(raw: Mapping[str, Any]) -> Dict[str, np.ndarray]:
    """The native module's buffers as numpy arrays: int64, or masked int64
    where the run ended before the instant (the CSV's empty cells)."""
    cols: Dict[str, np.ndarray] = {}
    for name, value in raw.items():
        if isinstance(value, tuple):
            data, mask = value
            cols[name] = np.ma.MaskedArray(
                np.frombuffer(data, dtype="<i8"), mask=np.frombuffer(mask, dtype=np.bool_)
            )
        else:
            cols[name] = np.frombuffer(value, dtype="<i8")
    cols["chain"] = cols["chain"].astype(np.int32)
    return cols


R = TypeVar("R", bound=Report)



def _finish(command: str, result: Tuple[Any, ...], kind: Type[R]) -> R:
    """A native reply as the typed report a method returns."""
    report, status, notes, cols, designed, tables = result
    for note in notes:
        (log.error if note.startswith("error") else log.info)(note)
    if report is None:
        # No report: the command failed, and its notes say why.
        text = "\n".join(notes) or f"{command} failed with exit status {status}"
        raise (InputError if status == 2 else InternalError)(text)
    report["exit_status"] = status
    if cols is not None:
        report["samples"] = Table("samples", _columns(cols))
    if command == "design":
        report["spec"] = System(designed) if designed is not None else None
    return kind(report, {name: table_from_raw(name, raw) for name, raw in tables.items()})


def campaign(
    config: Union[str, "os.PathLike[str]"],
    out: Union[str, "os.PathLike[str]"],
    *,
    shard: Union[str, Tuple[int, int], None] = None,
    jobs: Optional[int] = None,
    plan: bool = False,
) -> Union[CampaignSummary, CampaignPlan]:
    """Runs a campaign (``rtpipe campaign CONFIG OUTDIR --json``): its
    systems generated, analysed and simulated on ``jobs`` threads (every
    core by default) into Parquet shards in ``out``; shards already there
    are skipped (only complete shards of this campaign count; a directory
    of another campaign raises ``InputError``). ``shard=(i, n)`` (or
    ``"i/n"``) runs only the shards ``k % n == i``; ``plan=True`` only
    counts the part's shards (``part_shards``) and lists those ``out``
    holds whole (``written``) and those it holds damaged (``rerun``)
    without running any.
    """
    options = dict(shard=_shard(shard), jobs=jobs, plan=plan)

    def call() -> Union[CampaignSummary, CampaignPlan]:
        flags = [os.fspath(config), os.fspath(out)] + _flags(options, _switches(campaign))
        result = _rtpipe.run_plain("campaign", flags)
        if plan:
            return _finish("campaign", result, CampaignPlan)
        return _finish("campaign", result, CampaignSummary)

    return _speaking_python(list(inspect.signature(campaign).parameters), call)


def _shard(shard: Union[str, Tuple[int, int], None]) -> Optional[str]:
    """``shard`` as ``--shard``'s ``i/n``: a string is the command line's
    to check; a tuple must be ``(index, count)`` with ``0 <= index < count``
    (anything else would run a part the caller did not ask for)."""
    if shard is None or isinstance(shard, str):
        return shard
    pair = isinstance(shard, tuple) and len(shard) == 2
    if pair and not any(isinstance(x, bool) for x in shard):
        try:
            # Any integer (numpy's too), but not a float or a string.
            index, count = (operator.index(x) for x in shard)
            if 0 <= index < count:
                return f"{index}/{count}"
        except TypeError:
            pass
    raise ValueError(
        f"campaign(shard={shard!r}): give a 2-tuple (index, count) of ints with "
        "0 <= index < count, such as shard=(0, 4) for the first of four parts"
    )


def _samples(
    samples: Union[bool, str, "os.PathLike[str]", None], options: Dict[str, Any]
) -> bool:
    """``samples``: True returns the rows as columns (held in memory, at most
    :data:`MAX_SAMPLE_ROWS`); a path streams them to that CSV file instead
    (``--samples``, any number of rows), added to ``options``."""
    if samples is None or isinstance(samples, bool):
        return bool(samples)
    if isinstance(samples, (str, os.PathLike)):
        options["samples"] = samples
        return False
    raise TypeError(
        f"samples={samples!r}: give True (numpy columns) or a path (a CSV file streamed as "
        "the run goes)"
    )


class System:
    """A loaded spec: its tasks and chains, and the commands that run on it."""

    def __init__(self, handle: "_rtpipe.Spec"):
        self._spec = handle

    def __reduce__(self) -> Tuple[Any, ...]:
        # The native spec pickles as its TOML: a Pool or Ray ships systems.
        return (System, (self._spec,))

    @property
    def name(self) -> str:
        return self._spec.name

    @property
    def tasks(self) -> Tasks:
        """The task names, in the spec's order (a list's equality, length,
        iteration and positions); ``tasks["gyro"]`` is that :class:`Task`,
        whose keys are attributes: ``system.tasks["gyro"].period = "2ms"``
        edits the system."""
        return Tasks(self)

    @property
    def chains(self) -> Chains:
        """The chain labels, in the spec's order (the ``chain`` column of
        ``samples`` indexes this list); ``chains[label]`` is that
        :class:`Chain`: ``system.chains["P1"].reaction = "120ms"``."""
        return Chains(self)

    def _edit(self, keys: List[Union[str, int]], value: Any, shown: str) -> None:
        """Sets the spec's value at ``keys`` (None removes it) once the
        spec's validation accepts the result; an error names ``shown``, and
        the system stays as it was."""
        self._spec = self._spec.edit(keys, value, shown)

    @property
    def free_tasks(self) -> List[str]:
        """Tasks without a fixed period: what :meth:`design` chooses."""
        return self._spec.free_tasks()

    def to_toml(self) -> str:
        """The spec as TOML (as ``design --write`` writes it)."""
        return self._spec.to_toml()

    def __repr__(self) -> str:
        return repr(self._spec)

    def _run(
        self, command: str, options: Mapping[str, Any], kind: Type[R], samples: bool = False
    ) -> R:
        method = getattr(System, command)
        keywords = list(inspect.signature(method).parameters)[1:]

        def call() -> R:
            flags = _flags(options, _switches(method))
            return _finish(command, _rtpipe.run(command, self._spec, flags, samples), kind)

        return _speaking_python(keywords, call)

    def _run_samples(
        self, command: str, options: Dict[str, Any], samples: Any, kind: Type[R]
    ) -> R:
        columns = _samples(samples, options)
        return self._run(command, options, kind, columns)

    def analyze(
        self,
        *,
        mode: Optional[str] = None,
        all_paths: bool = False,
        margins: bool = False,
        margins_csv: Union[str, "os.PathLike[str]", None] = None,
        observed: Union[str, "os.PathLike[str]", None] = None,
    ) -> AnalysisReport:
        """Schedulability and the worst-case bounds of every chain
        (``rtpipe analyze --json``); ``mode`` ("sound" or "paper") decides
        ``ok``. ``margins=True`` adds ``"margins"`` (``--margins``): how much
        each exec may grow, each chain limit's slack, the critical scaling
        factors and each period's range, under ``mode``; ``margins_csv``
        also writes them to that CSV file (``--margins-csv``). ``observed``
        adds ``"observed"`` (``--observed``): the measured latencies of that
        CSV file (a ``--samples`` file, or a flight log's data ages) against
        the bounds; ``exit_status`` is 1 when one exceeds its sound bound."""
        options = dict(
            mode=mode,
            all_paths=all_paths,
            margins=margins,
            margins_csv=margins_csv,
            observed=observed,
        )
        return self._run("analyze", options, AnalysisReport)

    def simulate(
        self,
        *,
        outputs: Optional[int] = None,
        duration: Union[str, float, None] = None,
        seed: Optional[int] = None,
        exec: Optional[str] = None,
        phasing: Optional[str] = None,
        search_steps: Optional[int] = None,
        samples: Union[bool, str, "os.PathLike[str]"] = False,
        trace: Optional[str] = None,
        plot: Optional[str] = None,
        gantt: Optional[str] = None,
        window: Optional[str] = None,
    ) -> SimulationReport:
        """The simulator against the bounds (``rtpipe simulate --json``).

        ``samples=True`` adds ``"samples"``: one numpy column per field of
        ``--samples`` (``chain``, ``sample``, ``read_ns``, ``event_ns``,
        ``first_output_ns``, ``last_output_ns``, ``reaction_ns``,
        ``freshness_ns``, ``event_reaction_ns``, ``event_freshness_ns``),
        masked where the run ended first. They are held in memory: a run with
        more than :data:`MAX_SAMPLE_ROWS` rows is stopped there with
        MemoryError. ``samples="FILE.csv"`` streams any number of rows to
        that file instead (``--samples``; nothing of it stays when the call
        fails or is interrupted). ``trace``, ``plot`` and ``gantt`` write
        files as the flags do.
        """
        options = dict(
            outputs=outputs, duration=duration, seed=seed, exec=exec, phasing=phasing,
            search_steps=search_steps, trace=trace, plot=plot, gantt=gantt, window=window,
        )
        return self._run_samples("simulate", options, samples, SimulationReport)

    def fly(
        self,
        *,
        vehicle: Optional[str] = None,
        mission: Optional[str] = None,
        turbulence: Optional[str] = None,
        duration: Union[str, float, None] = None,
        seed: Optional[int] = None,
        exec: Optional[str] = None,
        samples: Union[bool, str, "os.PathLike[str]"] = False,
        plot: Optional[str] = None,
        log: Optional[str] = None,
        sweep: bool = False,
        scale: Optional[str] = None,
        per_octave: Optional[int] = None,
        seeds: Optional[int] = None,
        phases: Optional[int] = None,
        pass_rate: Optional[float] = None,
        confidence: Optional[float] = None,
        resolution: Optional[float] = None,
        check_step: Optional[float] = None,
        safety: Optional[float] = None,
        criterion: Optional[str] = None,
        write_limits: Optional[str] = None,
        free_periods: bool = False,
    ) -> Union[FlightReport, SweepReport]:
        """A software-in-the-loop flight on the simulated schedule
        (``rtpipe fly --json``), or with ``sweep=True`` the timing sweep
        that derives the limits the flight depends on: ``seeds`` ×
        ``phases`` flights a timing, judged all-pass or by ``pass_rate``
        (at ``confidence``), each edge refined to ``resolution`` and
        checked below on a ladder of ``check_step`` (0.02 by default; 0
        turns the check off), the limits × ``safety``. ``samples`` as in
        :meth:`simulate`."""
        options = dict(
            vehicle=vehicle, mission=mission, turbulence=turbulence, duration=duration,
            seed=seed, exec=exec, plot=plot, log=log, sweep=sweep, scale=scale,
            per_octave=per_octave, seeds=seeds, phases=phases, pass_rate=pass_rate,
            confidence=confidence, resolution=resolution, check_step=check_step,
            safety=safety, criterion=criterion, write_limits=write_limits,
            free_periods=free_periods,
        )
        if sweep:
            return self._run_samples("fly", options, samples, SweepReport)
        return self._run_samples("fly", options, samples, FlightReport)

    def run(
        self,
        *,
        duration: Union[str, float, None] = None,
        policy: Optional[str] = None,
        best_effort: bool = False,
        force: bool = False,
        synthetic: bool = False,
        vehicle: Optional[str] = None,
        mission: Optional[str] = None,
        load: Optional[int] = None,
        samples: Union[str, "os.PathLike[str]", None] = None,
        trace: Union[str, "os.PathLike[str]", None] = None,
        plot: Union[str, "os.PathLike[str]", None] = None,
        export_rt_app: Union[str, "os.PathLike[str]", None] = None,
    ) -> RunReport:
        """Runs the spec for real on this machine (``rtpipe run --json``):
        one thread per task under ``policy`` ("fifo", "deadline",
        "edf-fifo"; "other" with ``best_effort=True`` runs without real-time
        privileges), for ``duration`` (default 2 s, a flight's mission
        plus 5 s when the tasks name flight bodies and ``synthetic`` is
        False). The real-time classes need root (CAP_SYS_NICE): without it
        the kernel refuses them and this raises ``RunError`` (an
        ``InputError``) saying so.
        ``samples``, ``trace``, ``plot`` and ``export_rt_app`` write files
        as the flags do. Ctrl-C (or SIGTERM, SIGHUP) ends the run early, as
        on the command line, and raises KeyboardInterrupt once its threads
        are stopped and its files written."""
        options = dict(
            duration=duration, policy=policy, best_effort=best_effort, force=force,
            synthetic=synthetic, vehicle=vehicle, mission=mission, load=load, samples=samples,
            trace=trace, plot=plot, export_rt_app=export_rt_app,
        )
        # The runtime catches the stop signals itself while its threads run
        # (it must stop them, not be unwound past them): Python's handlers
        # are put back after it.
        kept = _signal_handlers()
        try:
            report = self._run("run", options, RunReport)
        finally:
            _restore_signal_handlers(kept)
        if report.run.interrupted:
            raise KeyboardInterrupt("the run was stopped by a signal")
        return report

    def design(
        self,
        *,
        mode: Optional[str] = None,
        method: Optional[str] = None,
        solver: Optional[str] = None,
        time_limit: Optional[float] = None,
        fly: Union[str, Sequence[str], None] = None,
        vehicle: Union[str, Sequence[str], None] = None,
        seed: Optional[int] = None,
        flights: Optional[int] = None,
        pass_rate: Optional[float] = None,
        confidence: Optional[float] = None,
        write: Optional[str] = None,
        overwrite_spec: bool = False,
        objective: Optional[str] = None,
        max_utilization: Optional[float] = None,
        margins: bool = False,
    ) -> DesignReport:
        """Periods that meet every limit at least utilisation
        (``rtpipe design --json``), plus ``"spec"``: the designed
        :class:`System`, or None when there is no verified design.
        ``objective="margin"`` with ``max_utilization=U`` asks instead for
        the largest factor every exec may grow by together within that
        utilisation (``design["margin_search"]``); ``margins=True`` adds
        the answer's timing margins (``"margins"``, as ``analyze``).
        With ``fly``, ``seed`` is the first seed of each vehicle and
        mission's flights, and a design is accepted when the Wilson lower
        bound of its pass rate reaches ``pass_rate`` at ``confidence``
        (defaults 0.95 and 0.95: 73 flights), over ``flights`` flights."""
        options = dict(
            mode=mode, method=method, solver=solver, time_limit=time_limit, fly=fly,
            vehicle=vehicle, seed=seed, flights=flights, pass_rate=pass_rate,
            confidence=confidence, write=write, overwrite_spec=overwrite_spec,
            objective=objective, max_utilization=max_utilization, margins=margins,
        )
        return self._run("design", options, DesignReport)


# What a keyword means where it is not the command line's flag as it is:
# Python's own arguments, and flags whose value Python takes differently.
_PYTHON_ARGUMENTS: Dict[str, str] = {
    "samples": (
        "True returns the sample rows as numpy columns (``report.samples``, at "
        "most MAX_SAMPLE_ROWS of them, else MemoryError); a path streams any "
        "number of rows to that CSV file instead, as the command line's flag does."
    ),
    "config": "The campaign's config file (TOML).",
    "out": "The directory its Parquet shards go to (made if missing).",
    "shard": "Only the shards ``k % n == i``: a 2-tuple ``(i, n)`` or the string ``\"i/n\"``.",
    "fly": "A mission (or a list of them) to fly every candidate design on (``--fly``).",
    "vehicle": "A vehicle (or a list of them) to fly (``--vehicle``).",
}


def _document(function: Callable[..., Any], command: str) -> None:
    """Ends ``function``'s docstring with an ``Arguments:`` section: each
    keyword, what the command line's help says of its flag (flags named
    as keywords), or what :data:`_PYTHON_ARGUMENTS` says of a keyword
    Python takes its own way. The help is the clap definitions', so the
    two cannot drift apart."""
    import textwrap

    keywords = [k for k in inspect.signature(function).parameters if k != "self"]
    helps = dict(_rtpipe.flag_help(command))
    lines = ["", "Arguments:"]
    for key in keywords:
        flag = key.replace("_", "-")
        text = _PYTHON_ARGUMENTS.get(key) if command != "waters" else None
        text = text or helps.get(flag) or _PYTHON_ARGUMENTS.get(key)
        if text is None:
            raise AssertionError(f"{function.__qualname__}({key}=...) has no help to show")
        said = _pythonic(" ".join(text.split()), keywords)
        wrapped = textwrap.wrap(f"{key}: {said}", width=76, subsequent_indent="    ")
        lines.extend("    " + w for w in wrapped)
    function.__doc__ = (inspect.getdoc(function) or "") + "\n" + "\n".join(lines) + "\n"


for _command in ("analyze", "simulate", "fly", "run", "design"):
    _document(getattr(System, _command), _command)
_document(campaign, "campaign")
_document(waters, "waters")
del _command
