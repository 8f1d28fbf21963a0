"""Dataset code: importers of external data (HOMER+)."""
