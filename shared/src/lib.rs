//! Mesh model and file formats shared by `sfcb` and `mpm-solve`.
//!
//! - [`model`]: the Anura3D model (geometry plus every GOM section, typed where understood);
//! - [`gom`]: Anura3D `.GOM` reader and writer; [`cps`]: Anura3D `.CPS` reader;
//! - [`bms`]: Anura3D benchmark tables (`.BMS`, `.BMR`) reader; [`anura3d_vtk`]: Anura3D's
//!   material-point VTK output reader;
//! - [`msh`]: Gmsh `.msh` reader (2.2 and 4.1, ASCII and binary) and conversion to the model;
//! - [`vtu`]: ParaView VTU and PVD writers; [`vtu_read`]: their reader (raw appended VTU, PVD);
//! - [`points`]: material-point ids and input element numbers that survive reordering;
//! - [`geometry`]: signed tetrahedron volumes;
//! - [`suite`]: where tests find Anura3D's benchmark suite and binary;
//! - [`coincident`]: coincident duplicate nodes, found and described for a warning;
//! - [`io`]: standard input/output and atomic file writes; [`text`]: scanning and formatting.
#![warn(missing_docs)]

pub mod anura3d_vtk;
pub mod bms;
pub mod coincident;
pub mod cps;
pub mod error;
pub mod generate;
pub mod geometry;
pub mod gom;
pub mod io;
pub mod model;
pub mod msh;
pub mod points;
pub mod suite;
pub mod text;
pub mod vtu;
pub mod vtu_read;

pub use error::{Error, Location, Result};
pub use model::{Dimension, ElementType, Model};

/// Reads a GOM file (`-` for standard input).
pub fn read_gom_file(path: &std::path::Path) -> Result<Model> {
    let data = io::map_input(path)?;
    gom::read(&data, &display_name(path))
}

/// Writes a GOM file atomically (`-` for standard output).
pub fn write_gom_file(model: &Model, path: &std::path::Path) -> Result<()> {
    io::write_output_with(path, |w| gom::write_to(model, w))
}

/// The name of `path` as shown in messages.
pub fn display_name(path: &std::path::Path) -> String {
    if io::is_stdio(path) {
        "<stdin>".to_string()
    } else {
        path.display().to_string()
    }
}

/// Mesh file formats recognised by [`read_model`] and [`write_model`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Anura3D geometry (`.GOM`, `.GOM_stageN`, any case).
    Gom,
    /// Gmsh mesh (`.msh`).
    Msh,
    /// ParaView unstructured grid (`.vtu`, output only).
    Vtu,
}

/// The format named by a path's extension (`None` for `-` or an unknown extension).
pub fn format_of(path: &std::path::Path) -> Option<Format> {
    let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
    let ext = name.rsplit_once('.')?.1;
    if ext == "gom" || ext.starts_with("gom_stage") {
        Some(Format::Gom)
    } else if ext == "msh" {
        Some(Format::Msh)
    } else if ext == "vtu" {
        Some(Format::Vtu)
    } else {
        None
    }
}

/// Reads a mesh as a model: GOM or Gmsh MSH, chosen by extension, or by content for `-` and
/// unknown extensions (`$MeshFormat` starts an MSH file, `###` a GOM).
pub fn read_model(path: &std::path::Path) -> Result<Model> {
    let data = io::map_input(path)?;
    let name = display_name(path);
    let format = match format_of(path) {
        Some(Format::Vtu) => {
            return Err(Error::Unsupported {
                at: Location::new(&name, 0, None),
                message: "reading .vtu (inputs are .GOM or .msh)".into(),
            })
        }
        Some(f) => f,
        None => {
            let start = data
                .iter()
                .position(|&b| !b.is_ascii_whitespace())
                .unwrap_or(0);
            if data[start..].starts_with(b"$MeshFormat") {
                Format::Msh
            } else if data[start..].starts_with(b"###") {
                Format::Gom
            } else {
                return Err(Error::format(
                    Location::new(&name, 1, None),
                    "not a GOM ('### Anura3D_...' first line) or Gmsh file ('$MeshFormat'); name it .GOM or .msh",
                ));
            }
        }
    };
    match format {
        Format::Msh => msh::to_model(&msh::read(&data, &name)?, &name),
        _ => gom::read(&data, &name),
    }
}

/// Writes a model as GOM (`.GOM`, `.GOM_stageN`, `-` for standard output) or VTU (`.vtu`, with
/// `material` and, when given, `partition` cell data). The file appears only once complete.
pub fn write_model(model: &Model, path: &std::path::Path, partition: Option<&[i32]>) -> Result<()> {
    match format_of(path) {
        Some(Format::Vtu) => io::write_output_with(path, |w| {
            vtu::write_model(w, model, partition, vtu::Encoding::Appended)
        }),
        Some(Format::Gom) => write_gom_file(model, path),
        None if io::is_stdio(path) => write_gom_file(model, path),
        _ => Err(Error::Unsupported {
            at: Location::new(&display_name(path), 0, None),
            message: "output format; name the output .GOM, .GOM_stageN, .vtu or -".into(),
        }),
    }
}
