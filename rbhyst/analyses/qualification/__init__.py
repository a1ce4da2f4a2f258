"""Qualification to the standards: required response spectra (rrs), spectrum-compatible motions
(matching), random vibration from a PSD (psd) and the verdict of a deck against them (verdict)."""
