"""What is imaged: point scatterers (per A-line or shared), regions, deformation and mechanics."""
