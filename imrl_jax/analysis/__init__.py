"""Analysis of lives (section 3): behaviour and what experts follow, the hand-written controllers, a learning
test's steady state, the claims' verdict rules on measured numbers, and the figures.

Imports ``evolution``, ``agent``, ``world`` and the layer below; writes no run directory.
"""
