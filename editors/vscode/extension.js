// Starts `bgc lsp` for .bg files. The server does the work; this only tells VS Code how to run it.
const vscode = require("vscode");
const { LanguageClient, TransportKind } = require("vscode-languageclient/node");

let client;

function serverOptions() {
  const config = vscode.workspace.getConfiguration("bgc");
  const command = config.get("path", "bgc");
  const include = config.get("includeDirectories", []);
  const args = include.flatMap((dir) => ["-I", dir]).concat(["lsp"]);
  // TransportKind.stdio makes the client add `--stdio`, which `bgc lsp` accepts.
  return { command, args, transport: TransportKind.stdio };
}

async function activate(context) {
  client = new LanguageClient(
    "bgc",
    "bgc language server",
    serverOptions(),
    { documentSelector: [{ scheme: "file", language: "bg" }, { scheme: "untitled", language: "bg" }] }
  );
  context.subscriptions.push(
    vscode.workspace.onDidChangeConfiguration(async (e) => {
      if (e.affectsConfiguration("bgc") && client) {
        await client.stop();
        client = new LanguageClient("bgc", "bgc language server", serverOptions(), client.clientOptions);
        await client.start();
      }
    })
  );
  await client.start();
}

async function deactivate() {
  if (client) {
    await client.stop();
  }
}

module.exports = { activate, deactivate };
