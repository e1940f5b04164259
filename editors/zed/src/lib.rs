//! Starts bgc's language server for `.bg` files: the binary set in Zed's settings
//! (`"lsp": { "bgc": { "binary": { "path": "...", "arguments": [...] } } }`), else `bgc` found on the `PATH` of the
//! worktree's shell, with the argument `lsp`.

use zed_extension_api::{self as zed, LanguageServerId, Result, settings::LspSettings};

struct BgcExtension;

impl zed::Extension for BgcExtension {
    fn new() -> Self {
        BgcExtension
    }

    fn language_server_command(
        &mut self,
        language_server_id: &LanguageServerId,
        worktree: &zed::Worktree,
    ) -> Result<zed::Command> {
        let binary = LspSettings::for_worktree(language_server_id.as_ref(), worktree)
            .ok()
            .and_then(|settings| settings.binary);
        let configured_path = binary.as_ref().and_then(|b| b.path.clone());
        let command = match configured_path {
            Some(path) => path,
            None => worktree.which("bgc").ok_or_else(|| {
                "bgc was not found on the PATH: install it (`cargo install --path bgc`) or set \
                 lsp.bgc.binary.path in Zed's settings"
                    .to_string()
            })?,
        };
        let args = binary
            .and_then(|b| b.arguments)
            .unwrap_or_else(|| vec!["lsp".to_string()]);
        Ok(zed::Command {
            command,
            args,
            env: worktree.shell_env(),
        })
    }
}

zed::register_extension!(BgcExtension);
