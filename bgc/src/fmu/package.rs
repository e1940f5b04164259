//! The Rust crate of an FMU's library: the generated model module, the fixed C interface of `template/`, and the
//! manifest, with the model identifier and GUID that `modelDescription.xml` names.

use super::Version;
use super::description::{Header, model_description};
use super::structure::dependencies;
use super::variables::variables;
use crate::codegen::{CompiledFile, CompiledModel, Fnv1a, rust};

/// The files of an FMU's crate and what its description says.
#[derive(Clone, Debug)]
pub struct Sources {
    /// The model identifier: the library's file name in the FMU and the prefix-free C names.
    pub identifier: String,
    pub guid: String,
    /// The crate's package name (unique per model and version, so that crates share a target directory).
    pub crate_name: String,
    /// The library target's name (`lib<lib_name>.so`).
    pub lib_name: String,
    pub description: String,
    /// `(path in the crate, text)`.
    pub files: Vec<(String, String)>,
}

const TEMPLATE: [(&str, &str); 9] = [
    (
        "src/fmi3_absent.rs",
        include_str!("template/fmi3_absent.rs"),
    ),
    ("src/ffi.rs", include_str!("template/ffi.rs")),
    (
        "src/fmi2_solving.rs",
        include_str!("template/fmi2_solving.rs"),
    ),
    (
        "src/fmi3_solving.rs",
        include_str!("template/fmi3_solving.rs"),
    ),
    ("src/instance.rs", include_str!("template/instance.rs")),
    ("src/plant.rs", include_str!("template/plant.rs")),
    ("src/solver.rs", include_str!("template/solver.rs")),
    ("src/fmi2.rs", include_str!("template/fmi2.rs")),
    ("src/fmi3.rs", include_str!("template/fmi3.rs")),
];

/// The most states an FMU takes: its Co-Simulation solver holds the dense state Jacobian and its LU decomposition
/// on the heap (2 · N² · 8 bytes, 256 MiB at 4,096 states) and decomposes it at every step (N³/3 flops).
const MAX_STATES: usize = 4096;

/// The crate of model `model` of `file` (the only one when `None`) for FMI `version`; `source_name` names the file
/// in the generated module's header.
pub fn package_sources(
    file: &CompiledFile,
    model: Option<&str>,
    version: Version,
    source_name: &str,
) -> Result<Sources, String> {
    let chosen = match (model, file.models.as_slice()) {
        (None, [one]) => one,
        (None, many) => {
            let names: Vec<&str> = many.iter().map(|m| m.model.name.as_str()).collect();
            return Err(format!(
                "declares several models ({}); choose one with --model",
                names.join(", ")
            ));
        }
        (Some(name), many) => many.iter().find(|m| m.model.name == name).ok_or_else(|| {
            let names: Vec<&str> = many.iter().map(|m| m.model.name.as_str()).collect();
            format!("has no model `{name}`; it declares {}", names.join(", "))
        })?,
    };
    check_size(chosen)?;
    let identifier = identifier(&chosen.model.name);
    let guid = guid(file.hash, &chosen.model.name, version);
    let vars = variables(chosen);
    let description = model_description(
        version,
        &Header {
            model_name: &chosen.model.name,
            identifier: &identifier,
            guid: &guid,
            description: (!chosen.model.doc.is_empty()).then(|| chosen.model.doc.join(" ")),
        },
        &vars,
        &dependencies(&chosen.equations),
    );
    let single = CompiledFile {
        models: vec![chosen.clone()],
        warnings: Vec::new(),
        hash: file.hash,
    };
    let module = rust::generate_with(&single, source_name, rust::Options { runtime: false });
    let tag = match version {
        Version::Fmi2 => "fmi2",
        Version::Fmi3 => "fmi3",
    };
    let lib_name = format!("bgc_fmu_{identifier}_{tag}");
    let crate_name = lib_name.replace('_', "-");
    let mut files = vec![
        (
            "Cargo.toml".to_string(),
            manifest(&crate_name, &lib_name, tag),
        ),
        (
            "src/lib.rs".to_string(),
            include_str!("template/lib.rs").replace("@GUID@", &guid),
        ),
        ("src/model.rs".to_string(), module),
    ];
    files.extend(TEMPLATE.iter().map(|(p, t)| (p.to_string(), t.to_string())));
    Ok(Sources {
        identifier,
        guid,
        crate_name,
        lib_name,
        description,
        files,
    })
}

/// Refuses a model too large for an FMU: more than [`MAX_STATES`] states, or Jacobian functions that keep a matrix
/// larger than the generated code's bound on the importer's stack (`Plan::oversized_stack_matrix`).
fn check_size(chosen: &CompiledModel) -> Result<(), String> {
    let name = &chosen.model.name;
    let states = chosen.equations.states.len();
    if states > MAX_STATES {
        let mib = states * states * 8 * 2 / (1024 * 1024);
        return Err(format!(
            "model `{name}` has {states} states: an FMU's Co-Simulation solver holds the {states} x {states} state \
             Jacobian and its LU decomposition ({mib} MiB) and decomposes it at every step, so `bgc fmu` exports \
             models of at most {MAX_STATES} states; simulate it with `bgc simulate`, or generate its Rust module \
             with `bgc rust`"
        ));
    }
    if let Some((bytes, rows)) = chosen.plan.oversized_stack_matrix() {
        let (kib, bound) = (bytes / 1024, rust::MAX_CONSTANT_JACOBIAN_BYTES / 1024);
        return Err(format!(
            "model `{name}` has {states} states: its Jacobian functions keep a matrix of {rows} by states, \
             inputs or outputs ({kib} KiB) on the stack of the importing tool's thread, more than the {bound} KiB an FMU allows; \
             simulate it with `bgc simulate`, or generate its Rust module with `bgc rust`"
        ));
    }
    Ok(())
}

/// The manifest: the library as a `cdylib`, with the crates the generated module needs (the versions bgc's own
/// workspace uses), optimised, and a workspace of its own wherever it lies. nalgebra comes without its default
/// features: the generated code needs only `core` (see `codegen::rust`), the solver decomposes its matrices
/// itself (nalgebra decomposes fixed sizes only up to 127), and without the `macros` feature the build compiles
/// no proc-macro crates (`syn` and its kin), the larger part of a first FMU build.
fn manifest(crate_name: &str, lib_name: &str, feature: &str) -> String {
    format!(
        "# Generated by bgc {version}: the library of an FMU.\n\
         [package]\nname = \"{crate_name}\"\nversion = \"0.1.0\"\nedition = \"2024\"\npublish = false\n\n\
         [lib]\nname = \"{lib_name}\"\ncrate-type = [\"cdylib\"]\npath = \"src/lib.rs\"\n\n\
         [features]\ndefault = [\"{feature}\"]\nfmi2 = []\nfmi3 = []\n\n\
         [dependencies]\nnalgebra = {{ version = \"0.35\", default-features = false, features = [\"libm\"] }}\nlibm = \"0.2\"\n\n\
         [profile.release]\nopt-level = 2\ndebug = false\npanic = \"unwind\"\n\n\
         [workspace]\n",
        version = rust::BGC_VERSION
    )
}

/// The model identifier: the model's name with every character outside `[A-Za-z0-9_]` replaced by `_`, and `_`
/// before a leading digit (a C identifier and a file name on every platform).
pub fn identifier(name: &str) -> String {
    let mut id: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if id.is_empty() || id.starts_with(|c: char| c.is_ascii_digit()) {
        id.insert(0, '_');
    }
    id
}

/// A GUID from the model's sources (their hash), its name, the FMI version and bgc's version: the same model
/// gives the same GUID, any change a different one.
fn guid(hash: u64, model: &str, version: Version) -> String {
    let half = |salt: &str| {
        let mut h = Fnv1a::new();
        h.write(salt.as_bytes());
        h.write(&hash.to_le_bytes());
        h.write(model.as_bytes());
        h.write(format!("{version:?} {}", rust::BGC_VERSION).as_bytes());
        h.finish()
    };
    let (a, b) = (half("guid-high"), half("guid-low"));
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_are_c_names() {
        assert_eq!(identifier("back_support"), "back_support");
        assert_eq!(identifier("2-link arm"), "_2_link_arm");
        assert_eq!(identifier(""), "_");
    }

    #[test]
    fn guid_has_the_registry_form() {
        let g = guid(1, "m", Version::Fmi2);
        assert_eq!(g.len(), 38);
        assert_ne!(g, guid(2, "m", Version::Fmi2));
        assert_ne!(g, guid(1, "m", Version::Fmi3));
    }
}
