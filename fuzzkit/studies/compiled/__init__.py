"""The closed loop compiled as one numba function: plant period, faults, latency, controller.

:func:`fuzzkit.studies.compiled.loop.run_compiled` is the compiled twin of
:func:`fuzzkit.studies.runner.run` for the 6-DOF plant (``arm6``) and the pymunk planar arm
(``planar``, ``planar_loop.py``); the run's controller is its spec's generated C. The Python
runner stays the reference and ``tests/test_compiled_loop.py`` holds the two to the same force
traces.
"""
