"""Report writing shared by every crosscheck: tables, HTML pages, the verify index."""
