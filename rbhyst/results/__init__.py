"""Layer 4, results: what is made of a finished run. Its checks and warnings, the files it
is written to (time_history.csv, summary.json, spectra.csv), and the analysis of a deck from
start to end (:mod:`.analysis`), which everything built on runs calls."""
