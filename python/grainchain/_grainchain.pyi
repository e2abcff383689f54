"""Type stubs of the compiled module ``grainchain._grainchain`` (Rust, PyO3). The public names
are re-exported by ``grainchain`` and its namespaces ``analysis``, ``problems`` and
``protector``."""

import os
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_PathLike = Union[str, "os.PathLike[str]"]
_SceneLike = Union["Scene", str, "os.PathLike[str]", Mapping[str, Any]]
_F64 = npt.NDArray[np.float64]
_I64 = npt.NDArray[np.int64]

class SceneError(ValueError):
    """A scene that cannot be used (file, key, what is wrong)."""

    file: str
    key: Optional[str]

class DesignError(ValueError):
    """A protector design, load or setting that cannot be evaluated (place and key)."""

    design: Optional[int]
    bead: Optional[int]
    key: str

class RunError(RuntimeError):
    """A run that could not be set up or failed."""

class BlowUpError(RunError):
    """A numerical blow-up, with its time, step and printed grain number."""

    time: float
    step: int
    grain: int

class StudyError(RuntimeError):
    """A study, reproduce or output folder that failed."""

class InternalError(RuntimeError):
    """A Rust panic caught at the boundary."""

class Scene:
    """A checked scene."""

    @staticmethod
    def load(path: _PathLike, *, allow_large_output: bool = False) -> "Scene": ...
    @staticmethod
    def from_toml(text: str, name: str = "<string>", *, allow_large_output: bool = False) -> "Scene": ...
    @staticmethod
    def from_dict(d: Mapping[str, Any], *, allow_large_output: bool = False) -> "Scene": ...
    @property
    def name(self) -> str: ...
    @property
    def description(self) -> str: ...
    @property
    def path(self) -> str: ...
    @property
    def grains(self) -> int: ...
    @property
    def outputs(self) -> int: ...
    @property
    def duration(self) -> float: ...
    @property
    def output_interval(self) -> float: ...
    @property
    def method(self) -> str: ...
    @property
    def dt(self) -> float: ...
    @property
    def regions(self) -> List[Tuple[str, Tuple[int, int]]]: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def toml(self) -> str: ...
    def check(self) -> Dict[str, Any]: ...

def check(scene: _SceneLike, *, allow_large_output: bool = False) -> Dict[str, Any]:
    """The estimate ``grainchain check`` prints."""

def _run(
    scene: _SceneLike,
    *,
    on_output: Optional[Any] = None,
    allow_large_output: bool = False,
) -> Dict[str, Any]: ...
def _panic_for_test(message: str) -> None: ...

# problems
def problem_names() -> List[str]: ...
def problem(name: str) -> Dict[str, Any]: ...
def run_problem(name: str, *, scenes: _PathLike = ...) -> Dict[str, Any]: ...

# analysis
def log_bins(
    e: _F64, lo: int = 1, hi: Optional[int] = None, per_decade: int = 20
) -> Dict[str, npt.NDArray[Any]]: ...
def fit_power_law(bins: Mapping[str, Any]) -> Optional[Dict[str, float]]: ...
def leak_onset(e: _F64, fraction: float = 0.5) -> Optional[int]: ...
def collapse_alpha(
    reference: Mapping[str, Any],
    curve: Mapping[str, Any],
    *,
    min_overlap_decades: float = 0.3,
    alpha_min: float = 0.02,
    alpha_max: float = 50.0,
    points_per_decade: int = 40,
) -> Optional[Dict[str, float]]: ...
def ensemble_bands(members: _F64) -> Dict[str, _F64]: ...
def ensemble_gamma(
    members: _F64, lo: int, hi: int, per_decade: int = 20
) -> Optional[Dict[str, float]]: ...
def local_slope(
    e: _F64, lo: int = 1, hi: Optional[int] = None, per_decade: int = 10, half_width: int = 2
) -> Dict[str, _F64]: ...

# harness
def study(
    sweep: _PathLike,
    *,
    out: Optional[_PathLike] = None,
    threads: Optional[int] = None,
    shard: Optional[str] = None,
    resume: bool = False,
    force: bool = False,
    allow_large_output: bool = False,
) -> Dict[str, Any]: ...
def reproduce(
    *,
    out: _PathLike = ...,
    scenes: _PathLike = ...,
    only: Optional[Sequence[str]] = None,
    snapshots: Optional[int] = None,
    threads: int = 2,
    force: bool = False,
) -> Dict[str, Any]: ...

# protector
def protector_materials() -> Dict[str, Dict[str, float]]: ...
def protector_evaluate(
    beads: Sequence[Any],
    *,
    striker: Any,
    speed: float,
    wall: Optional[Any] = None,
    target: Optional[Mapping[str, Any]] = None,
    restitution: Optional[float] = None,
    restitution_pairs: Optional[Sequence[Any]] = None,
    need: str = "peak",
    fraction: Optional[float] = None,
    accuracy: Optional[float] = None,
    steps_per_contact: Optional[float] = None,
    check_every: Optional[int] = None,
    time_cap: Optional[float] = None,
    give_up_above: Optional[float] = None,
    gradients: bool = False,
) -> Dict[str, Any]: ...
def protector_evaluate_many(
    designs: Any,
    *,
    striker: Any,
    speed: float,
    wall: Optional[Any] = None,
    target: Optional[Mapping[str, Any]] = None,
    restitution: Optional[float] = None,
    restitution_pairs: Optional[Sequence[Any]] = None,
    need: str = "peak",
    fraction: Optional[float] = None,
    accuracy: Optional[float] = None,
    steps_per_contact: Optional[float] = None,
    check_every: Optional[int] = None,
    time_cap: Optional[float] = None,
    give_up_above: Optional[float] = None,
    threads: int = 1,
) -> Dict[str, npt.NDArray[Any]]: ...
def protector_monte_carlo(
    beads: Sequence[Any],
    *,
    striker: Any,
    speed: float,
    tolerances: Mapping[str, float],
    samples: int,
    seed: int = 1,
    stream: int = 0,
    statistic: str = "p95",
    wall: Optional[Any] = None,
    target: Optional[Mapping[str, Any]] = None,
    restitution: Optional[float] = None,
    restitution_pairs: Optional[Sequence[Any]] = None,
    accuracy: Optional[float] = None,
    steps_per_contact: Optional[float] = None,
    check_every: Optional[int] = None,
    time_cap: Optional[float] = None,
    threads: int = 1,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> Dict[str, Any]: ...
def protector_estimate(
    beads: Sequence[Any],
    *,
    striker: Any,
    speed: float,
    wall: Optional[Any] = None,
    target: Optional[Mapping[str, Any]] = None,
    restitution: Optional[float] = None,
    restitution_pairs: Optional[Sequence[Any]] = None,
    need: str = "peak",
    fraction: Optional[float] = None,
    accuracy: Optional[float] = None,
    steps_per_contact: Optional[float] = None,
    check_every: Optional[int] = None,
    time_cap: Optional[float] = None,
    to_end: bool = False,
) -> Dict[str, Any]: ...
