"""The agent of section 2: its perceptrons, their learning, the state a phase carries, and whole lives (childhood
and adulthood) as the XLA step, the Pallas kernel and the NumPy reference; brax's agents as baselines.

Imports ``world`` and the layer below it.
"""
