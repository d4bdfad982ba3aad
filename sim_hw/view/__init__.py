"""Seeing a world: ``mover view`` (a running world, live) and ``mover replay`` (a recording), in
rerun's web viewer (the optional ``view`` extra: ``pip install 'mover[view]'``).

* :mod:`sim_hw.view._scene` — what every world process answers a viewer (``view.scene``, and
  ``view.frame`` for a grid); no rerun needed, so worlds export it whether or not the extra is
  installed;
* :mod:`sim_hw.view._entities` — a scene and its frames as rerun entities (``Drawing``);
* :mod:`sim_hw.view._live` — the observer node that draws a running world;
* :mod:`sim_hw.view._server` — rerun's server (gRPC proxy and web page) as a child process;
* :mod:`sim_hw.view.cli` — the ``view`` verb, and the viewer half of ``replay``.

Nothing here imports rerun until a view is shown.
"""

from sim_hw.view._scene import FRAME, SCENE, export_scene

__all__ = ["FRAME", "SCENE", "export_scene"]
