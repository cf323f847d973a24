//! The README demo (`glsl/grid_demo.comp`): a procedural pinhole grid seen through a lens,
//! computed per output pixel with the GPU Newton inverse — no source image involved.
