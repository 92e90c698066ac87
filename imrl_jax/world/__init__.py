"""The world of section 2: the arena's floor and walls, the retina, the task sets, and a task as an environment.

Imports only the layer below (``config``, ``conditions``, ``genome``, ``files``); knows nothing of the agent.
"""
