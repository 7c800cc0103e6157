"""CI regression: golden files, comparing runs with them, JUnit XML and the pytest plugin."""
