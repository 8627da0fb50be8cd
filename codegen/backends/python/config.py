"""Python target: which templates make which files (``{name}`` is the rule base name)."""

#: Lookup-table method.
FILES = {"{name}.py": "module.py.jinja"}

#: Exact method (``--method exact``): the inference itself, no table.
EXACT_FILES = {"{name}.py": "exact.py.jinja"}
