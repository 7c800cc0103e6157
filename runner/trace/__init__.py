"""Stage 4, the trace: the MCAP writer, its Foxglove encoding, and the writer in a second process.

The format both sides agree on is :mod:`reports.trace_format`; readers are in :mod:`reports`.
"""
