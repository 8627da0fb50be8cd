"""The C target: jinja2 templates for NAME.h and NAME.c."""
