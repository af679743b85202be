"""Registers the commands that live beside their subpackages on the ``aerodock`` app."""
