"""The pure-Python target: a jinja2 template for one standalone module."""
