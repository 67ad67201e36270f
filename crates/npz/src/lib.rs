//! Writing numpy `.npz` archives in pure Rust, so that numpy users load a
//! simulation or a sweep in one line (`numpy.load("run.npz")`).
//!
//! An `.npz` file is a ZIP archive whose members are `.npy` files, one per
//! array (numpy's `savez`). The members are encoded by `npyz` (the `.npy`
//! format: magic, header dict with dtype, order and shape, then the data
//! little-endian) and stored uncompressed by the `zip` crate without its
//! default features (no C compression libraries).
//!
//! ```
//! let mut out = npz::NpzWriter::new(std::io::Cursor::new(Vec::new()));
//! out.add_f64("times", &[3], &[0.0, 0.5, 1.0]).unwrap();
//! out.add_i64("counts", &[2, 2], &[1, 2, 3, 4]).unwrap();
//! let bytes = out.finish().unwrap().into_inner();
//! assert_eq!(&bytes[..4], b"PK\x03\x04"); // a ZIP archive
//! // The first member's data starts with the .npy magic.
//! let npy = bytes.windows(6).position(|w| w == b"\x93NUMPY").unwrap();
//! assert!(npy < 100);
//! assert!(npz::NpzWriter::new(std::io::Cursor::new(Vec::new())).add_f64("x", &[2], &[1.0]).is_err());
//! ```
#![warn(missing_docs)]

use npyz::WriterBuilder;
use std::io::{self, Seek, Write};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipWriter};

/// An `.npz` archive being written to `W`.
pub struct NpzWriter<W: Write + Seek> {
    zip: ZipWriter<W>,
}

fn invalid(message: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, message)
}

impl NpzWriter<std::fs::File> {
    /// Create (or truncate) the file at `path`.
    pub fn create(path: &std::path::Path) -> io::Result<Self> {
        Ok(NpzWriter::new(std::fs::File::create(path)?))
    }
}

impl<W: Write + Seek> NpzWriter<W> {
    /// An empty archive on `w`.
    pub fn new(w: W) -> Self {
        NpzWriter { zip: ZipWriter::new(w) }
    }

    fn add<T: npyz::AutoSerialize + Copy>(&mut self, name: &str, shape: &[u64], data: &[T]) -> io::Result<()> {
        let count: u64 = shape.iter().product();
        if count != data.len() as u64 {
            return Err(invalid(format!("{name}: shape {shape:?} holds {count} values, got {}", data.len())));
        }
        if name.is_empty() || name.contains(['/', '\\']) || name.contains("..") {
            return Err(invalid(format!("{name:?}: not a plain array name")));
        }
        let mut npy = Vec::new();
        let mut writer = npyz::WriteOptions::new().default_dtype().shape(shape).writer(&mut npy).begin_nd()?;
        writer.extend(data.iter().copied())?;
        writer.finish()?;
        let options = SimpleFileOptions::default().compression_method(CompressionMethod::Stored).large_file(false);
        self.zip.start_file(format!("{name}.npy"), options).map_err(io::Error::other)?;
        self.zip.write_all(&npy)
    }

    /// Add the `f64` array `name` (C order, `shape`'s product values).
    pub fn add_f64(&mut self, name: &str, shape: &[u64], data: &[f64]) -> io::Result<()> {
        self.add(name, shape, data)
    }

    /// Add the `i64` array `name`.
    pub fn add_i64(&mut self, name: &str, shape: &[u64], data: &[i64]) -> io::Result<()> {
        self.add(name, shape, data)
    }

    /// Write the ZIP central directory and return the writer.
    pub fn finish(self) -> io::Result<W> {
        self.zip.finish().map_err(io::Error::other)
    }
}
