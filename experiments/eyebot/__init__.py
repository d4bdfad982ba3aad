"""Cooperative stigmergic navigation (Ducatelle et al., sections 5–7), in-process and seeded.

Eye-bots on the ceiling learn, from what they see of the foot-bots below, to instruct them on
their way between a source and a target. A run (:mod:`._trial`) is 3000 simulated seconds on
the pymunk world with the ceiling layer above it; the arenas (:mod:`._arena`) are the cluttered
room of Fig. 1(c) and the double corridor of Fig. 3.

Figures: ``fig2`` (t_1, t_a and t_s against the number of foot-bots, the cluttered arena),
``fig3`` (ρ histograms for r = 1, 1.5, 2, 15 foot-bots deployed one every 30 s), ``fig4`` (ρ
histograms for 1 to 30 foot-bots, equal corridors), ``fig5`` (t_a against ρ, from Fig. 4's runs
with 10, 20 and 30 foot-bots) and ``beyond`` (trip-time weights, the paper's future work, on
unequal corridors with 20 and 30 foot-bots). Every run's seed derives from the master seed
(printed) and the run's index; runs are saved per point as JSON lines and read back
(``--save``), so that a later invocation adds runs.
"""

from ._cli import register, run, settings

__all__ = ["register", "run", "settings"]
