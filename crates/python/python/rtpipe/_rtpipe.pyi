"""Type stubs of the native module (crates/python/src/lib.rs)."""

from typing import Any, Dict, List, Optional, Tuple, Union

__version__: str
COMMANDS: List[str]
# Every command of the binary: (its path, the function or method that
# calls it or None, why none does or None).
REACH: List[Tuple[str, Optional[str], Optional[str]]]
MAX_SAMPLE_ROWS: int

class RtpipeError(Exception): ...

class SpecError(RtpipeError):
    file: str
    # The first problem's place, message and fix (None where unknown).
    line: Optional[int]
    column: Optional[int]
    key: Optional[str]
    message: Optional[str]
    fix: Optional[str]
    # Each problem: {"message": str, "help": str | None, "line": int | None,
    # "column": int | None, "key": str | None}
    diagnostics: List[Dict[str, Any]]

class InputError(RtpipeError):
    message: str
    help: Optional[str]
    # The keyword argument at fault, when the message names one.
    argument: Optional[str]

class RunError(InputError): ...

class InternalError(RtpipeError): ...

class Spec:
    @property
    def name(self) -> str: ...
    @property
    def label(self) -> str: ...
    @property
    def tasks(self) -> List[str]: ...
    @property
    def chains(self) -> List[str]: ...
    def free_tasks(self) -> List[str]: ...
    def to_toml(self) -> str: ...
    def get(self, keys: List[Union[str, int]]) -> Any: ...
    def edit(self, keys: List[Union[str, int]], value: Any, at: str) -> Spec: ...
    def __reduce__(self) -> Tuple[Any, Tuple[str, str]]: ...

def load_path(path: str) -> Spec: ...
def load_text(text: str, label: str) -> Spec: ...
def dict_to_toml(value: Dict[str, Any]) -> str: ...

# The raw sample columns: little-endian int64 buffers, with a mask buffer
# (one byte per row, 1 where the cell is empty) for the optional columns.
RawColumns = Dict[str, Union[bytes, Tuple[bytes, bytes]]]

# A report's tables: name -> (column names, {column: (dtype, data, mask)}),
# data a little-endian buffer (a list of str for dtype "str"), mask one byte
# per row (1 where the cell is empty) or None.
RawTables = Dict[str, Tuple[List[str], Dict[str, Tuple[str, Any, Optional[bytes]]]]]

def run(
    command: str,
    spec: Spec,
    flags: List[str],
    samples: bool = False,
    max_samples: Optional[int] = None,
) -> Tuple[
    Optional[Dict[str, Any]], int, List[str], Optional[RawColumns], Optional[Spec], RawTables
]: ...
def run_plain(
    command: str, flags: List[str]
) -> Tuple[Optional[Dict[str, Any]], int, List[str], None, None, RawTables]: ...
def flag_help(command: str) -> List[Tuple[str, str]]: ...
def waters(flags: List[str]) -> Spec: ...
def make(
    command: str, flags: List[str], text: Optional[str] = None
) -> Tuple[Any, List[str], List[Tuple[str, Spec]], Dict[str, str]]: ...
