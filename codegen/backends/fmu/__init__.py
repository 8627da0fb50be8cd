"""FMU target: the whole controller as an FMI 2.0 Co-Simulation FMU (C sources + binary)."""
