"""The bottom of the house: what every layer above may import and what imports nothing of the package above it.

`contract` is the host/device contract (the struct layouts of kernels/types.h, their type codes, the wavelength
grid, buffer layouts), `parameters` the vocabulary every plugin's parameter table is written in, `limits` the
bounds the scene format puts on numbers. tests/test_layers.py holds the rule.
"""
