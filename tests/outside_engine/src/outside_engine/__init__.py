"""A minimal engine outside the runner's tree: free rigid bodies in pure numpy (``engine``), registered with
physics-scenarios through an entry point (``registration``, which imports nothing of the engine)."""
