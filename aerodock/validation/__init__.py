"""Validation of aerodock's models against independent simulators (peers)."""
