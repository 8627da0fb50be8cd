"""The verification report: tuned and default gains, every experiment on every plant, verdicts.

Sits above studies and visualisation (it runs the studies and draws their figures); only the CLI
imports it.
"""
