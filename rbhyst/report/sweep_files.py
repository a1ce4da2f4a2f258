"""The names of the sweep's figures (rbhyst.report.sweep draws them), for a caller that must
know them without importing matplotlib."""

PLOT_FILES = ("ida.png", "vary.png", "motions.png")
