"""File and device formats: logs (CSV, Parquet), the atomic writer, bags, the Net F/T, sources.

Formats only: nothing here runs the estimator (the runs are :mod:`softtip.apps`). Import a
name from the module that defines it: :mod:`~softtip.io.tables` (read and write logs and
result tables), :mod:`~softtip.io.formats` (recognised log dialects and units),
:mod:`~softtip.io.atomic` (safe writing), :mod:`~softtip.io.bag` (ROS bags),
:mod:`~softtip.io.netft` (ATI Net F/T and Axia), :mod:`~softtip.io.sources` (sample sources),
:mod:`~softtip.io.payload` (gravity-compensated logs and sources),
:mod:`~softtip.io.examples` (the example data).
"""
