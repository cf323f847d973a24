//! The camera-file readers and writers on files written here in each tool's layout: which
//! camera of a file, every model of the table from its tool's own file, and every format a
//! camera converts into, read back to the same pixels.

mod camera_catalog;
mod model_files;
