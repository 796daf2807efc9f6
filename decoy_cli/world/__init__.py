"""Map geometry: the built-in de_dust2 world from the nav mesh, user meshes, pybullet loading."""
