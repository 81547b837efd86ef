"""pytest-benchmark suite for the hot kernels (not part of the default test run).

Run with ``make bench-kernels`` or ``pytest benchmarks --benchmark-only``.
"""
