"""The report's pages by subject; each module draws its pages from data and builds them from a ``Context``."""
