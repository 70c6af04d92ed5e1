"""Performance benchmarks (pytest-benchmark), skipped in the default test run.

Run them with:  pytest tests/benchmarks --benchmark-only
"""
