"""Random rough surfaces: generation of profiles and height maps, and their measurement."""
