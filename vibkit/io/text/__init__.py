"""The text reader: CSV, TSV, logger and spreadsheet exports.

:func:`vibkit.io.text.csv.read_csv` reads a text recording; the modules beside it each do one part:

* :mod:`~vibkit.io.text.layout`: decoding, dialect (delimiter, decimal mark) and the header row;
* :mod:`~vibkit.io.text.cells`: what a cell holds (number, missing, time stamp, comment);
* :mod:`~vibkit.io.text.fastpath`: the rows of a clean file parsed by pandas' C reader;
* :mod:`~vibkit.io.text.metadata`: ``key: value`` lines above the data (sample rate, counts scale);
* :mod:`~vibkit.io.text.columns` and :mod:`~vibkit.io.text.timecolumn`: channels and the time column;
* :mod:`~vibkit.io.text.units`: units written in headers, and their conversion to SI;
* :mod:`~vibkit.io.text.loggers`: what each known logger or app writes without saying it (one entry each).

Nothing is imported here, so that :mod:`vibkit.io` loads the text reader only when a text file is read.
"""
