"""Point-cloud file formats (read and write) below curv.io."""
