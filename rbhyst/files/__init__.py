"""Layer 1, files: reading text files, the units their headers declare, and writing output
folders safely (only rbhyst's own files are ever replaced). Imports nothing of rbhyst above
``errors``."""
