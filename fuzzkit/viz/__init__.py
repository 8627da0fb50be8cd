"""Visualisation: control surfaces (PNG and Rerun) and Rerun recordings of closed-loop runs.

Imports studies (run results), plants (geometry) and the fuzzy core; never the report or the CLI.
"""
