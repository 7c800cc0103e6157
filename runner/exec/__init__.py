"""Running cases elsewhere: child processes, local pools and Ray, with one way of reporting how a case ended."""
