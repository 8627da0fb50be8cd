"""The numba side of the loop: the per-period pieces every compiled loop shares (``period``),
the generated controller called by address (``generated_controller``), each plant's loop over
periods (``arm6_run``, ``planar_run``), and what turns their recording into a run result
(``common``). :func:`fuzzkit.loop.compiled_loop.run_compiled` runs them; the Python loop
(:func:`fuzzkit.loop.python_loop.run`) stays the reference, and ``tests/test_compiled_loop.py``
holds the two to the same force traces.
"""
