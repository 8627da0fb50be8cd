"""The one closed loop: a run specification in, a run result out.

:func:`fuzzkit.loop.run.run_loop` is the entry point (``fuzzkit simulate``, ``compare``, ``sweep``,
``tune``, ``report``, ``stability --simulate``, the latency sweep and ``make bench`` call it);
:mod:`fuzzkit.loop.choice` holds the one rule for which controller implementation runs; each
plant is an adapter module (``planar``, ``arm6``, ``mujoco``) registered in
:mod:`fuzzkit.loop.adapter`. The loop imports control, plants, codegen and the planar arm,
never studies, analysis, viz, report or the CLI.
"""
