"""Cooperative stigmergic navigation (Ducatelle et al., sections 5–7), in-process and seeded.

Eye-bots on the ceiling learn, from what they see of the foot-bots below, to instruct them on
their way between a source and a target. A run (:mod:`._trial`) is 3000 simulated seconds on
the pymunk world with the ceiling layer above it; the arenas (:mod:`._arena`) are the cluttered
room of Fig. 1(c) and the double corridor of Fig. 3.
"""
