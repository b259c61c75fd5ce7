"""The bases of the typed results (``rtpipe.reports``, generated from the
Rust report structs) and the tables that come with them.

A result is a ``dict``: exactly what the command's ``--json`` prints (plus
``exit_status``, and ``samples`` and ``spec`` where asked), so
``report["chains"][0]["sound"]`` works as it always did, ``json.dumps``
takes it and ``to_dict()`` returns the plain dict. Its fields are also
properties (``report.chains[0].sound``) typed and documented from the Rust
doc comments. A report's tables (what ``--format csv`` prints) are
:class:`Table` columns under :attr:`Report.tables`, with ``to_pandas``,
``to_polars`` and ``to_arrow``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Dict, List, Mapping, Optional, Tuple, TypeVar, cast

import numpy as np

if TYPE_CHECKING:  # pragma: no cover - for the type checker only
    from . import System

T = TypeVar("T")


def maybe(wrap: Callable[[Any], T], value: Any) -> Optional[T]:
    """``wrap(value)``, or None for None (a null or absent field)."""
    return None if value is None else wrap(value)


def each(wrap: Callable[[Any], T], value: Any) -> List[T]:
    """Every item of a JSON list, wrapped."""
    return [wrap(v) for v in value]


def values(wrap: Callable[[Any], T], value: Any) -> Dict[str, T]:
    """Every value of a JSON object whose keys are data, wrapped."""
    return {k: wrap(v) for k, v in value.items()}


class Record(Dict[str, Any]):
    """An object of a report: a dict of its JSON fields, each also a
    property of the generated subclass."""

    def to_dict(self) -> Dict[str, Any]:
        """The plain dict (the nested objects plain too): what the method
        returned before results were typed, and what ``--json`` prints."""
        return cast(Dict[str, Any], _plain(self))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({dict.__repr__(self)})"


def _plain(value: Any) -> Any:
    if isinstance(value, Table):
        return dict(value)
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


def _optional(package: str, module: str, purpose: str) -> Any:
    """Imports ``module``, or raises ImportError saying which pip package
    brings it (pandas, polars and pyarrow are optional)."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as e:
        raise ImportError(
            f"{purpose} needs {package}, which is not installed: pip install {package}"
        ) from e


class Table(Dict[str, np.ndarray]):
    """Columns of one table: ``name -> numpy array`` (a dict, in column
    order), every column as long as :attr:`rows`. Numeric columns are
    read-only views of rtpipe's buffers (no copy); a column with empty
    cells (a CSV's empty fields) is a masked array; text is an object
    array of str. ``to_pandas``, ``to_polars`` and ``to_arrow`` build the
    frame (pandas, polars and pyarrow are optional installs)."""

    def __init__(self, name: str, columns: Mapping[str, np.ndarray]):
        super().__init__(columns)
        #: The table's name (``--format csv`` heads it with ``# name``).
        self.name = name

    @property
    def rows(self) -> int:
        """The number of rows."""
        return len(next(iter(self.values()))) if self else 0

    def to_arrow(self) -> Any:
        """The table as a ``pyarrow.Table`` (empty cells null; numeric
        columns without them are not copied)."""
        pa = _optional("pyarrow", "pyarrow", "Table.to_arrow()")
        arrays = []
        for col in self.values():
            if isinstance(col, np.ma.MaskedArray):
                arrays.append(pa.array(col.data, mask=np.ma.getmaskarray(col)))
            else:
                arrays.append(pa.array(col))
        return pa.Table.from_arrays(arrays, names=list(self.keys()))

    def to_pandas(self) -> Any:
        """The table as a ``pandas.DataFrame`` (integer columns with empty
        cells as pandas' nullable ``Int64``)."""
        pd = _optional("pandas", "pandas", "Table.to_pandas()")
        data: Dict[str, Any] = {}
        for name, col in self.items():
            if isinstance(col, np.ma.MaskedArray) and col.dtype.kind in "iu":
                mask = np.ma.getmaskarray(col).copy()
                data[name] = pd.arrays.IntegerArray(np.asarray(col.data), mask)
            elif isinstance(col, np.ma.MaskedArray):
                data[name] = col.filled(np.nan)
            else:
                data[name] = col
        return pd.DataFrame(data, columns=list(self.keys()))

    def to_polars(self) -> Any:
        """The table as a ``polars.DataFrame`` (empty cells null)."""
        pl = _optional("polars", "polars", "Table.to_polars()")
        return pl.from_arrow(self.to_arrow())

    def __repr__(self) -> str:
        return f"<rtpipe table {self.name!r}: {self.rows} rows, columns {list(self.keys())}>"


def table_from_raw(name: str, raw: Tuple[List[str], Mapping[str, Any]]) -> Table:
    """A table of the native module's (names, {name: (dtype, data, mask)})."""
    names, cols = raw
    out: Dict[str, np.ndarray] = {}
    for col in names:
        dtype, data, mask = cols[col]
        if dtype == "str":
            arr = np.array(data, dtype=object)
        else:
            arr = np.frombuffer(data, dtype=dtype)
        if mask is not None:
            arr = np.ma.MaskedArray(arr, mask=np.frombuffer(mask, dtype=np.bool_))
        out[col] = arr
    return Table(name, out)


class Report(Record):
    """A command's whole report: its JSON fields, plus ``exit_status`` (the
    command line's), ``samples`` when asked, and its :attr:`tables`."""

    _tables: Dict[str, Table]

    def __init__(self, data: Mapping[str, Any], tables: Optional[Dict[str, Table]] = None):
        super().__init__(data)
        self._tables = dict(tables or {})

    @property
    def exit_status(self) -> int:
        """What the command line exits with: 0 ok, 1 a verdict failed (a
        limit missed, a flight that crashed), 2 a file could not be
        written (see the log)."""
        return int(self["exit_status"])

    @property
    def tables(self) -> Dict[str, Table]:
        """The report's tables by name, in order: what ``--format csv``
        prints (e.g. ``"tasks"`` and ``"chains"``)."""
        return self._tables

    @property
    def samples(self) -> Optional[Table]:
        """With ``samples=True``: one numpy column per field of
        ``--samples`` (times in integer nanoseconds, masked where the run
        ended first); else None."""
        value = self.get("samples")
        return value if isinstance(value, Table) else None

    def table(self, name: str) -> Table:
        """The table ``name`` (``"samples"`` for the sample columns), or
        KeyError listing the names there are."""
        if name == "samples" and self.samples is not None:
            return self.samples
        try:
            return self._tables[name]
        except KeyError:
            have = list(self._tables) + (["samples"] if self.samples is not None else [])
            raise KeyError(f"no table {name!r} in this report: it has {have}") from None

    def to_pandas(self, table: str) -> Any:
        """``self.table(table).to_pandas()``."""
        return self.table(table).to_pandas()

    def to_polars(self, table: str) -> Any:
        """``self.table(table).to_polars()``."""
        return self.table(table).to_polars()

    def to_arrow(self, table: str) -> Any:
        """``self.table(table).to_arrow()``."""
        return self.table(table).to_arrow()


class DesignBase(Report):
    """``design``'s report: its fields, plus the designed spec."""

    @property
    def spec(self) -> Optional["System"]:
        """The designed :class:`rtpipe.System` (its periods chosen), or None
        when there is no verified design."""
        return cast(Optional["System"], self.get("spec"))
