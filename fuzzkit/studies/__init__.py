"""Closed-loop studies: the experiments, the runner, metrics, plants by name, tuning.

Imports control and plants (and the formats, to load rule bases); never visualisation or the CLI.
"""
