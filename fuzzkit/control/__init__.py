"""Outer force-loop controllers: incremental PI, fuzzy-PI, the hybrid force/motion controller.

Also the controller spec, the sensor front end, adaptation and the gains files. Imports
:mod:`fuzzkit.fuzzy`, :mod:`fuzzkit.formats` and, for the path geometry of the impact-speed
check (:mod:`fuzzkit.control.impact`), the plants' environment types
(:mod:`fuzzkit.plants.environment`); no plant model, study or figure.
"""
