"""The editable views of a :class:`rtpipe.System`'s spec: ``system.tasks``
and ``system.chains``.

Indexed by position they are the lists of names they always were
(``system.tasks[0]``, ``list(system.tasks)``, ``system.tasks == ["a",
"b"]``); indexed by name they give a task or a chain whose attributes are
its spec keys (``system.tasks["gyro"].period = "2ms"``). An edit is checked
by the spec's one validation (the native module's, the same as a file's)
before it takes: a rejected edit raises :class:`rtpipe.InputError` naming
the attribute and the fix, and leaves the system as it was.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Iterator, List, Tuple, Union, overload

if TYPE_CHECKING:
    from . import System

#: A key path into the spec's tables: `["tasks", "gyro", "period"]`.
KeyPath = List[Union[str, int]]

#: The keys of a task a view reads and edits (docs/reference/spec.md).
TASK_KEYS = (
    "exec",
    "exec_min",
    "period",
    "max_period",
    "budget",
    "server",
    "serves",
    "cpu",
    "priority",
    "deadline",
    "jitter",
    "offset",
    "body",
    "reads",
    "thread",
    "activation",
    "triggers",
    "join",
)

#: The keys of a chain a view reads and edits: its limits, its semantics
#: and its path.
CHAIN_KEYS = (
    "reaction",
    "freshness",
    "max_reaction_time",
    "freshness_from_event",
    "communication",
    "path",
)


class _Item:
    """One task or chain of a system: its keys as attributes. Reading one
    gives the spec's value (None where the spec has none); setting one edits
    the system (None removes the key)."""

    _keys: Tuple[str, ...] = ()
    __slots__ = ("_system", "_path", "_shown")
    _system: "System"
    _path: KeyPath
    _shown: str

    def __init__(self, system: "System", path: KeyPath, shown: str):
        object.__setattr__(self, "_system", system)
        object.__setattr__(self, "_path", path)
        object.__setattr__(self, "_shown", shown)

    def __getattr__(self, key: str) -> Any:
        if key not in self._keys:
            raise AttributeError(self._unknown(key))
        return self._system._spec.get(self._path + [key])

    def __setattr__(self, key: str, value: Any) -> None:
        if key not in self._keys:
            raise AttributeError(self._unknown(key))
        self._system._edit(self._path + [key], value, f"{self._shown}.{key}")

    def __delattr__(self, key: str) -> None:
        self.__setattr__(key, None)

    def _unknown(self, key: str) -> str:
        return f"{self._shown} has no key {key!r}: the keys are {', '.join(self._keys)}"

    def __dir__(self) -> List[str]:
        return list(self._keys)

    def __repr__(self) -> str:
        values = {k: self._system._spec.get(self._path + [k]) for k in self._keys}
        shown = ", ".join(f"{k}={v!r}" for k, v in values.items() if v is not None)
        return f"<{self._shown}: {shown}>"


class Task(_Item):
    """A task of a system (``system.tasks["gyro"]``): ``period``, ``exec``,
    ``budget``, ``priority``, ``deadline``, ``cpu`` and its other spec keys
    (:data:`TASK_KEYS`) as attributes."""

    _keys = TASK_KEYS
    __slots__ = ()


class Chain(_Item):
    """A chain of a system (``system.chains["P1"]``, or by its label):
    its limits ``reaction``, ``freshness`` (from the head's read),
    ``max_reaction_time`` and ``freshness_from_event`` (from the event),
    ``communication`` and ``path`` as attributes."""

    _keys = CHAIN_KEYS
    __slots__ = ()


class _Names(Sequence[str]):
    """The names of a system's tasks or chains, in the spec's order; by
    name, the editable item."""

    def __init__(self, system: "System"):
        self._system = system

    def _names(self) -> List[str]:
        raise NotImplementedError

    def _item(self, name: str) -> _Item:
        raise NotImplementedError

    def __len__(self) -> int:
        return len(self._names())

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())

    @overload
    def __getitem__(self, key: int) -> str: ...
    @overload
    def __getitem__(self, key: slice) -> List[str]: ...
    @overload
    def __getitem__(self, key: str) -> Any: ...
    def __getitem__(self, key: Union[int, slice, str]) -> Any:
        if isinstance(key, str):
            if key not in self._names():
                raise KeyError(f"{key!r}: no such name; the names are {', '.join(self._names())}")
            return self._item(key)
        return self._names()[key]

    def __contains__(self, name: object) -> bool:
        return name in self._names()

    def __eq__(self, other: object) -> bool:
        if isinstance(other, _Names):
            other = list(other)
        if isinstance(other, (list, tuple)):
            return self._names() == list(other)
        return NotImplemented

    def __ne__(self, other: object) -> bool:
        equal = self.__eq__(other)
        return equal if equal is NotImplemented else not equal

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return repr(self._names())


class Tasks(_Names):
    """``system.tasks``: the task names (a list, as before); ``tasks[name]``
    is the editable :class:`Task`."""

    def _names(self) -> List[str]:
        return self._system._spec.tasks

    def _item(self, name: str) -> Task:
        return Task(self._system, ["tasks", name], f"system.tasks[{name!r}]")


class Chains(_Names):
    """``system.chains``: the chain labels (a list, as before; the ``chain``
    column of ``samples`` indexes it); ``chains[label]`` is the editable
    :class:`Chain`."""

    def _names(self) -> List[str]:
        return self._system._spec.chains

    def _item(self, name: str) -> Chain:
        index = self._names().index(name)
        return Chain(self._system, ["chain", index], f"system.chains[{name!r}]")
