"""The experiment runners of the papers and ``mover demo``: in-process, seeded, with reports.

``experiments.maze`` (Linardakis et al.: CU-LVP and its baselines) and
``experiments.foraging`` (Simonin et al.: c-marking and ants) run as
``mover experiment NAME`` (:mod:`experiments.cli`, the ``mover.experiments`` entry points) or
``python -m experiments.NAME``; :mod:`experiments.demo` is ``mover demo``. Unlike
``programs/``, this package may import the simulated hardware (``sim_hw``): it builds the
worlds the programs and agents run in.
"""
