//! Turns `drive.bg` into `$OUT_DIR/drive.rs` (see `src/main.rs` for the `include!`).

fn main() -> Result<(), bgc::build::Error> {
    bgc::build::compile(&["drive.bg"])?;
    Ok(())
}
