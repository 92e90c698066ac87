"""Evolution (section 2 "Genetic algorithm"): the search behind it (the paper's GA, evosax's strategies), sweeps
of dynamic values as one program, fitness landscapes, and the devices the lanes are laid out on.

Imports ``agent``, ``world`` and the layer below.
"""
