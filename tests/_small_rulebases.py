"""Pieces of small rule-base YAML the tests share (not a test module)."""

#: The 3 x 3 saturated-sum table over e (rows) and de (columns) with labels N, Z, P.
SUM_TABLE_3X3 = """\
rules:
  table:
    rows: e
    columns: de
    cells: |
      N N Z
      N Z P
      Z P P
"""
