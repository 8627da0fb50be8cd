"""Python target: which templates make which files (``{name}`` is the rule base name)."""

FILES = {
    "{name}.py": "module.py.jinja",
}
