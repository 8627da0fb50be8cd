"""C target: which templates make which files (``{name}`` is the rule base name)."""

#: Lookup-table method.
FILES = {
    "{name}.h": "header.h.jinja",
    "{name}.c": "source.c.jinja",
}

#: Exact method (``--method exact``): the inference itself, no table.
EXACT_FILES = {
    "{name}.h": "exact.h.jinja",
    "{name}.c": "exact.c.jinja",
}
