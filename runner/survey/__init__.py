"""`scenario robots survey`: real URDF and MJCF models, unmodified, on every engine (docs/robots.md)."""
