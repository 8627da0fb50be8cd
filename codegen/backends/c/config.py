"""C target: which templates make which files (``{name}`` is the rule base name)."""

FILES = {
    "{name}.h": "header.h.jinja",
    "{name}.c": "source.c.jinja",
}
