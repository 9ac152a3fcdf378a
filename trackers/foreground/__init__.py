"""Foreground: what in an image is the target's — background models, silhouettes, measured blobs."""
