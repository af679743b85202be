"""aerodock."""
