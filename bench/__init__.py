"""Benchmarks of the bogie library (not tests): ``python -m bench`` runs them all; see ``bench/README.md``."""
