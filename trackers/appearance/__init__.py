"""Colour: conversions, n-D histograms and their similarity, colour lookup tables."""
