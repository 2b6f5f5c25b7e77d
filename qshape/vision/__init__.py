"""Vision from images: relevant points of tiles from camera pictures, and the picture's health."""
