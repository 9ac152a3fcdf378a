"""Shared camera geometry."""
