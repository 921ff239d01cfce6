"""Pure-Python helpers: a model's body nodes and fields as pyvista or meshio point clouds.

Neither package is a dependency; each helper imports its package when called.
"""

from __future__ import annotations

import numpy as np


def fields_of(model, output=None):
    """The body fields as a dict of numpy arrays: ``temperature``, ``flux``, ``damage``,
    ``region``, ``spacing``, ``horizon``, ``volume`` (one entry per body node).

    ``output`` is one of the dicts ``Model.run`` returns; default: the model's state now.
    """
    nb = model.n_body
    if output is None:
        output = {
            "temperature": model.temperature[:nb],
            "flux": model.flux(),
            "damage": model.damage(),
        }
    return {
        "temperature": np.asarray(output["temperature"])[:nb],
        "flux": np.asarray(output["flux"]),
        "damage": np.asarray(output["damage"]),
        "region": model.region[:nb],
        "spacing": model.spacing[:nb],
        "horizon": model.horizon[:nb],
        "volume": model.volumes[:nb],
    }


def to_pyvista(model, output=None):
    """The body nodes as a ``pyvista.PolyData`` point cloud with the fields of
    :func:`fields_of` as point data (needs ``pip install pyvista``)."""
    import pyvista as pv

    cloud = pv.PolyData(model.positions[: model.n_body])
    for name, values in fields_of(model, output).items():
        cloud.point_data[name] = values
    return cloud


def to_meshio(model, output=None):
    """The body nodes as a ``meshio.Mesh`` of vertex cells with the fields of
    :func:`fields_of` as point data (needs ``pip install meshio``); write it with
    ``mesh.write("out.vtu")``."""
    import meshio

    nb = model.n_body
    cells = [("vertex", np.arange(nb, dtype=np.int64).reshape(-1, 1))]
    return meshio.Mesh(
        model.positions[:nb], cells, point_data=fields_of(model, output)
    )
