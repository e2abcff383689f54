"""The catalogue of sample problems with their reference values (Rust: ``grainchain_engine::problems``).

``names()`` lists them, ``get(name)`` gives the description and reference values, ``run(name)``
runs the problem's recommended simulation and returns its totals and final state as arrays.
"""

from ._grainchain import problem as get  # noqa: F401
from ._grainchain import problem_names as names  # noqa: F401
from ._grainchain import run_problem as run  # noqa: F401

__all__ = ["get", "names", "run"]
