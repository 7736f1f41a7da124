"""The scene: scatterers, their deformation, regions and mechanics."""
