"""peritherm from Python: transient heat conduction with dual-horizon peridynamics.

The native module ``peritherm._peritherm`` (PyO3) wraps the Rust library: ``Case``,
``Model`` (build, step, fields as numpy arrays, write), and ``run_case``, ``fem`` and
``sweep``, the CLI's subcommands as functions. ``to_pyvista`` and ``to_meshio`` turn a model
and its fields into meshes for plotting. See docs/python.md.
"""

from ._peritherm import Case, Model, __version__, fem, run_case, sweep
from ._helpers import fields_of, to_meshio, to_pyvista

__all__ = [
    "Case",
    "Model",
    "run_case",
    "fem",
    "sweep",
    "fields_of",
    "to_pyvista",
    "to_meshio",
    "__version__",
]
