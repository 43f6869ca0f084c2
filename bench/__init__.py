"""Benchmarks that print tables, and the plant corpus they score on (:mod:`bench.plants`)."""
