"""One module per paper table or figure; each prints a table and writes CSV/JSON + plots (spec §9)."""
