"""Runtime guards shared by every layer: safe outputs, budgets, kernel cache, progress, Dask clusters.

Imports only the standard library at load time.
"""
