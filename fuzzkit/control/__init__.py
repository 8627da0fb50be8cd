"""Outer force-loop controllers: incremental PI, fuzzy-PI, the hybrid force/motion controller.

Also the gains files. Imports :mod:`fuzzkit.fuzzy` and :mod:`fuzzkit.formats`; no plant, study or
figure.
"""
