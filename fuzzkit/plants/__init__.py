"""Simulated robots: the plant contract, environment, contact law, F/T sensor, the 6-DOF arm.

Knows no fuzzy logic and no controller (a controller is just whoever calls ``step``); the pymunk
planar arm, :mod:`fuzzkit.planar_sim`, implements the same contract.
"""
