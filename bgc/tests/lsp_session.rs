//! Sessions of `bgc lsp` driven by an in-process client: what an editor sees while the user opens, edits,
//! hovers, navigates, renames and formats `.bg` files.

use crate::lsp_support::{
    Client, apply, back_support_path, back_support_text, back_support_unacknowledged, code, edit,
    find, position_params, range, unsaved, uri,
};
use lsp_types::request::{
    CodeActionRequest, Completion, DocumentSymbolRequest, Formatting, GotoDefinition, HoverRequest,
    RangeFormatting, References, Rename,
};
use lsp_types::{
    CodeActionOrCommand, CompletionResponse, DiagnosticSeverity, DocumentSymbolResponse,
    GotoDefinitionResponse, HoverContents, Location, Position, TextDocumentIdentifier,
};

const LIB: &str = "component damper_pair {
    domain rotational;
    param k = 100 [N m/rad] \"stiffness\";
    0 j;
    1 rel;
    C spring = 1 / k;
    R damper = 2;
    bond j -> rel -> spring, damper;
    port a = j;
    port b = j;
}
";

const MAIN: &str = "import \"lib.bg\";

model rig {
    domain rotational;
    param k_rig = 50 [N m/rad] \"coupling stiffness\";
    input tau [N m] \"drive torque\";
    Se drive = tau;
    1 j1;
    I mass = 0.1;
    damper_pair pair(k = k_rig);
    Sf ground = 0;
    bond drive -> j1 -> mass, pair.a;
    bond ground -> pair.b;
    output torque [N m] = e(pair.spring) + e(pair.damper);
}
";

fn hover_text(client: &mut Client, uri: &lsp_types::Uri, at: Position) -> String {
    let hover = client
        .request::<HoverRequest>(lsp_types::HoverParams {
            text_document_position_params: position_params(uri, at),
            work_done_progress_params: Default::default(),
        })
        .expect("hover answers")
        .expect("something to show");
    match hover.contents {
        HoverContents::Markup(m) => m.value,
        other => panic!("markup expected, got {other:?}"),
    }
}

fn definition(client: &mut Client, uri: &lsp_types::Uri, at: Position) -> Location {
    let found = client
        .request::<GotoDefinition>(lsp_types::GotoDefinitionParams {
            text_document_position_params: position_params(uri, at),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .expect("definition answers");
    match found {
        Some(GotoDefinitionResponse::Scalar(l)) => l,
        other => panic!("one location expected, got {other:?}"),
    }
}

#[test]
fn initialize_offers_incremental_sync_in_utf16() {
    let client = Client::start();
    let caps = &client.initialize_result["capabilities"];
    assert_eq!(caps["positionEncoding"], "utf-16");
    assert_eq!(caps["textDocumentSync"]["change"], 2, "incremental");
    for provider in [
        "hoverProvider",
        "definitionProvider",
        "referencesProvider",
        "documentSymbolProvider",
        "documentFormattingProvider",
    ] {
        assert_eq!(caps[provider], true, "{provider}");
    }
    assert_eq!(caps["renameProvider"]["prepareProvider"], true);
    assert_eq!(client.initialize_result["serverInfo"]["name"], "bgc");
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
fn back_support_opens_with_its_two_derivative_causality_warnings() {
    let mut client = Client::start();
    let path = back_support_path();
    let doc = uri(&path);
    let text = back_support_unacknowledged();
    client.open(&doc, &text);
    let found = client.diagnostics(&doc, 1);
    // Without its `allow` lines, back_support.bg has exactly these two findings (the rigidly coupled gear inertia,
    // the trunk driven by a flow source), each at the element's declaration.
    let summary: Vec<(String, lsp_types::Range, Option<DiagnosticSeverity>)> = found
        .iter()
        .map(|d| (code(d), d.range, d.severity))
        .collect();
    let gear_in = find(&text, "I gear_in = J_g;", 0, 0);
    let trunk = find(&text, "I trunk = J_h;", 0, 0);
    assert_eq!(
        summary,
        vec![
            (
                "BG0510".to_string(),
                range(gear_in.line, 4, gear_in.line, 20),
                Some(DiagnosticSeverity::WARNING)
            ),
            (
                "BG0510".to_string(),
                range(trunk.line, 4, trunk.line, 18),
                Some(DiagnosticSeverity::WARNING)
            ),
        ]
    );
    assert_eq!((gear_in.line, trunk.line), (39, 69));
    assert!(
        found[0]
            .message
            .starts_with("inertia `gear_in` is in derivative causality")
    );
    assert!(
        found[0]
            .message
            .contains("\nhelp: `gear_in` and `rotor` are rigidly coupled")
    );
    let related = found[0]
        .related_information
        .as_ref()
        .expect("secondary labels");
    assert_eq!(
        related[0].location,
        Location::new(doc.clone(), range(38, 4, 38, 18))
    );
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
fn errors_are_published_with_exact_utf16_ranges_and_codes() {
    let mut client = Client::start();
    let doc = uri(&unsaved("errors.bg"));
    // `µ` takes two bytes and one UTF-16 unit: the unknown name `µ_J` spans columns 14 to 17.
    let text = back_support_text()
        .replace("I rotor = J_m;", "I rotor = µ_J;")
        .replace(
            "    bond trunk_motion -> j_h;",
            "    bond trunk_motion -> j_h;\n    param = 3 [1];",
        );
    client.open(&doc, &text);
    let found = client.diagnostics(&doc, 1);
    let summary: Vec<(String, lsp_types::Range)> =
        found.iter().map(|d| (code(d), d.range)).collect();
    let param_line = find(&text, "    param = 3", 0, 0).line;
    assert_eq!(
        summary,
        vec![
            ("BG0104".to_string(), range(38, 14, 38, 17)),
            ("BG0101".to_string(), range(param_line, 10, param_line, 11)),
            ("BG0201".to_string(), range(38, 14, 38, 17)),
        ],
        "{found:#?}"
    );
    assert!(
        found
            .iter()
            .all(|d| d.severity == Some(DiagnosticSeverity::ERROR))
    );
    assert!(
        found[0]
            .message
            .starts_with("name `µ_J` has a non-ASCII character")
    );
    assert!(
        found[1]
            .message
            .starts_with("expected the name of the parameter, found `=`")
    );
    assert!(found[2].message.starts_with("unknown name `µ_J`"));
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
fn incremental_changes_update_the_diagnostics_and_quick_fix_a_misspelling() {
    let mut client = Client::start();
    let doc = uri(&unsaved("back_support.bg"));
    let text = back_support_unacknowledged();
    client.open(&doc, &text);
    assert_eq!(client.diagnostics(&doc, 1).len(), 2);
    // `J_m` -> `J_n` in `I rotor = J_m;`, as a keystroke would: replace one character.
    let m = find(&text, "I rotor = J_m;", 0, 12);
    client.change(
        &doc,
        2,
        vec![edit(
            range(m.line, m.character, m.line, m.character + 1),
            "n",
        )],
    );
    let found = client.diagnostics(&doc, 2);
    assert_eq!(found.len(), 1, "{found:#?}");
    assert_eq!(
        (code(&found[0]), found[0].range),
        ("BG0201".to_string(), range(38, 14, 38, 17))
    );
    assert_eq!(
        found[0].message,
        "unknown name `J_n`\nhelp: did you mean `J_m`?"
    );

    let actions = client
        .request::<CodeActionRequest>(lsp_types::CodeActionParams {
            text_document: TextDocumentIdentifier::new(doc.clone()),
            range: range(38, 15, 38, 15),
            context: Default::default(),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .expect("code actions answer")
        .unwrap_or_default();
    assert_eq!(actions.len(), 1);
    let CodeActionOrCommand::CodeAction(fix) = &actions[0] else {
        panic!("a code action")
    };
    assert_eq!(fix.title, "Replace `J_n` with `J_m`");
    let edits = &fix
        .edit
        .as_ref()
        .and_then(|e| e.changes.as_ref())
        .expect("edits")[&doc];
    assert_eq!(edits.len(), 1);
    assert_eq!(
        (edits[0].range, edits[0].new_text.as_str()),
        (range(38, 14, 38, 17), "J_m")
    );

    // Two edits in one notification, the second in the text the first left: the fix, then `𝜔 ` (a character of
    // two UTF-16 units) at the start of the description of `J_m`, line 16.
    let quote = find(&text, "\"inertia of the brushless", 0, 1);
    assert_eq!(quote, Position::new(16, 34));
    client.change(
        &doc,
        3,
        vec![
            edit(range(38, 14, 38, 17), "J_m"),
            edit(range(16, 34, 16, 34), "𝜔 "),
        ],
    );
    assert_eq!(client.diagnostics(&doc, 3).len(), 2);
    // A second statement on that line, after the `𝜔`: the line was 74 units long and is 77 now, so the unknown
    // `J_q` in ` param J_z = J_q [1];` appended at its end spans columns 90 to 93.
    client.change(
        &doc,
        4,
        vec![edit(range(16, 77, 16, 77), " param J_z = J_q [1];")],
    );
    let found = client.diagnostics(&doc, 4);
    let unknown: Vec<_> = found
        .iter()
        .filter(|d| code(d) == "BG0201")
        .map(|d| d.range)
        .collect();
    assert_eq!(unknown, vec![range(16, 90, 16, 93)], "{found:#?}");
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
fn hover_shows_parameters_elements_causality_equations_and_units() {
    let mut client = Client::start();
    let path = back_support_path();
    let doc = uri(&path);
    let text = back_support_text();
    client.open(&doc, &text);
    client.diagnostics(&doc, 1);

    let param = hover_text(&mut client, &doc, find(&text, "param J_m", 0, 7));
    assert!(
        param.starts_with(
            "```bg\nparam J_m = 3.06e-4 [kg m^2] \"inertia of the brushless DC motor (I1)\";\n```"
        ),
        "{param}"
    );
    assert!(param.contains(
        "parameter `J_m` of model `back_support`: inertia of the brushless DC motor (I1)"
    ));
    assert!(
        param.contains("`J_m` = 3.06e-4 kg m^2 (SI; declared in [kg m^2])"),
        "{param}"
    );

    // A use of the parameter shows the same.
    assert_eq!(
        hover_text(&mut client, &doc, find(&text, "I rotor = J_m", 0, 11)),
        param
    );

    // The rotor: an inertia in integral causality, set by its 1-junction's flow; its state's rate is the line
    // `bgc equations` prints for it.
    let rotor = hover_text(&mut client, &doc, find(&text, "I rotor", 0, 3));
    let model = bgc_model(&text);
    let printed = bgc::equations::to_text(&model);
    let rate = printed
        .lines()
        .find(|l| l.trim_start().starts_with("d/dt p_rotor = "))
        .expect("the rotor's momentum is a state")
        .trim();
    assert!(
        rotor.contains("- I: inertia, stores kinetic energy"),
        "{rotor}"
    );
    assert!(rotor.contains("- `rotor` in model `back_support`: rotational domain"));
    assert!(rotor.contains("- integral causality (its energy variable is a state)"));
    assert!(
        rotor.contains("- `rotor` sets the flow on bond `j_m->rotor`"),
        "{rotor}"
    );
    assert!(rotor.contains(&format!("- `{rate}`")), "{rotor}\n{rate}");
    assert!(rotor.contains("- `f_rotor = p_rotor/J_m`"), "{rotor}");

    // The trunk's inertia, driven by a flow source: derivative causality.
    let trunk = hover_text(&mut client, &doc, find(&text, "I trunk", 0, 3));
    assert!(
        trunk.contains("- derivative causality (no state of its own)"),
        "{trunk}"
    );

    // The gearbox: a ratio of input over output speed gives f_out = f_in/r_g and, conserving power,
    // e_in = e_out/r_g. Its port variables are named `gear_in`/`gear_out`, so the inertia `gear_in` shows none.
    let gear = hover_text(&mut client, &doc, find(&text, "TF gear", 0, 3));
    assert!(gear.contains("- `f_gear_out = f_rotor/r_g`"), "{gear}");
    assert!(gear.contains("- `e_gear_in = e_gear_out/r_g`"), "{gear}");
    let gear_in = hover_text(&mut client, &doc, find(&text, "I gear_in", 0, 3));
    assert!(
        gear_in.contains("- derivative causality (no state of its own)"),
        "{gear_in}"
    );
    assert!(!gear_in.contains("e_gear_in ="), "{gear_in}");

    // An integrated flow: the motor angle integrates the flow of `j_m`, which is the rotor's.
    let theta = hover_text(&mut client, &doc, find(&text, "var theta_m", 0, 5));
    assert!(theta.contains("- unit [rad] = 1 in SI"), "{theta}");
    assert!(theta.contains("- `d/dt theta_m = f_rotor`"), "{theta}");

    // Units in their SI form: the radian is dimensionless.
    let unit = hover_text(&mut client, &doc, find(&text, "[rad/s]", 0, 1));
    assert_eq!(unit, "unit `[rad/s]` = 1/s (SI)");
    let kind = hover_text(&mut client, &doc, find(&text, "TF gear", 0, 0));
    assert_eq!(
        kind,
        "`TF`: transformer (`f_in = ratio f_out`, `e_out = ratio e_in`)"
    );
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

/// The equations of back_support through the library's pipeline, independently of the server.
fn bgc_model(text: &str) -> bgc::equations::Equations {
    let mut sources = bgc::span::SourceMap::new();
    let root = sources.add("back_support.bg", text);
    let (models, _) = bgc::lower::lower(&mut sources, root, &mut bgc::lower::MemoryLoader::new());
    let model = &models[0];
    let (causality, _) = bgc::causality::analyse(model);
    bgc::equations::derive(model, &causality).0
}

#[test]
fn definitions_and_references_within_a_file_and_into_the_standard_library() {
    let mut client = Client::start();
    let path = back_support_path();
    let doc = uri(&path);
    let text = back_support_text();
    client.open(&doc, &text);
    client.diagnostics(&doc, 1);
    assert_eq!(
        definition(&mut client, &doc, find(&text, "I rotor = J_m", 0, 11)),
        Location::new(doc.clone(), range(16, 10, 16, 13))
    );
    // An element named in a bond.
    assert_eq!(
        definition(&mut client, &doc, find(&text, "j_m -> rotor", 0, 8)),
        Location::new(doc.clone(), range(38, 6, 38, 11))
    );
    let refs = client
        .request::<References>(lsp_types::ReferenceParams {
            text_document_position: position_params(&doc, find(&text, "param k_g", 0, 6)),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
            context: lsp_types::ReferenceContext {
                include_declaration: true,
            },
        })
        .expect("references answer")
        .expect("references");
    assert_eq!(
        refs,
        vec![
            Location::new(doc.clone(), range(21, 10, 21, 13)),
            Location::new(doc.clone(), range(50, 24, 50, 27)),
        ]
    );

    let model = uri(&unsaved("uses_std.bg"));
    let source = "import \"std.bg\";\n\nmodel uses_std {\n    domain rotational;\n    Se drive = 1;\n    1 j1;\n    spring_damper_rot s(k = 5);\n    Sf ground = 0;\n    bond drive -> j1 -> s.a;\n    bond s.b -> ground;\n}\n";
    client.open(&model, source);
    client.diagnostics(&model, 1);
    let std_text = bgc::lower::STD_SOURCE;
    let component = definition(
        &mut client,
        &model,
        find(source, "spring_damper_rot s", 0, 3),
    );
    assert!(
        component.uri.as_str().ends_with("/std.bg"),
        "{:?}",
        component.uri
    );
    let decl = find(std_text, "component spring_damper_rot", 0, 10);
    assert_eq!(
        component.range,
        range(decl.line, decl.character, decl.line, decl.character + 17)
    );
    // The file it points at holds the standard library.
    let on_disk = bgc::lsp::files::uri_to_path(&component.uri).expect("a file URI");
    assert_eq!(
        std::fs::read_to_string(on_disk).ok().as_deref(),
        Some(std_text)
    );
    // The import itself leads to the file.
    let import = definition(&mut client, &model, Position::new(0, 9));
    assert_eq!(
        (import.uri, import.range),
        (component.uri.clone(), range(0, 0, 0, 0))
    );
    // A port of an instance, and an override's parameter.
    let port = definition(&mut client, &model, find(source, "s.a", 0, 2));
    let a = find(std_text, "port a = j;", 0, 5);
    assert_eq!(
        port.range,
        range(a.line, a.character, a.line, a.character + 1)
    );
    let k = definition(&mut client, &model, find(source, "(k = 5)", 0, 1));
    let k_decl = find(std_text, "param k = 1000 [N m/rad]", 0, 6);
    assert_eq!(
        k.range,
        range(
            k_decl.line,
            k_decl.character,
            k_decl.line,
            k_decl.character + 1
        )
    );
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
// The protocol keys a workspace edit's changes by `Uri`, whose cached parse is never changed once made.
#[allow(clippy::mutable_key_type)]
fn importers_see_unsaved_text_and_rename_reaches_them() {
    let mut client = Client::start();
    let lib = uri(&unsaved("lib.bg"));
    let main = uri(&unsaved("main.bg"));
    client.open(&lib, LIB);
    client.open(&main, MAIN);
    assert_eq!(client.diagnostics(&lib, 1), vec![]);
    assert_eq!(client.diagnostics(&main, 1), vec![]);
    assert_eq!(
        definition(&mut client, &main, Position::new(0, 10)),
        Location::new(lib.clone(), range(0, 0, 0, 0))
    );

    // A misspelling in the library, not saved: the importer's diagnostics show it at its import.
    let k_use = find(LIB, "1 / k;", 0, 4);
    client.change(
        &lib,
        2,
        vec![edit(
            range(k_use.line, k_use.character, k_use.line, k_use.character + 1),
            "kk",
        )],
    );
    let in_lib = client.diagnostics(&lib, 2);
    assert_eq!(
        in_lib
            .iter()
            .map(|d| (code(d), d.range))
            .collect::<Vec<_>>(),
        vec![("BG0201".to_string(), range(5, 19, 5, 21))]
    );
    let in_main = client.diagnostics(&main, 1);
    assert_eq!(in_main.len(), 1, "{in_main:#?}");
    assert_eq!(
        (code(&in_main[0]), in_main[0].range),
        ("BG0201".to_string(), range(0, 0, 0, 16))
    );
    assert!(
        in_main[0].message.starts_with("in `"),
        "{}",
        in_main[0].message
    );
    assert!(
        in_main[0].message.contains("lib.bg`: unknown name `kk`"),
        "{}",
        in_main[0].message
    );
    let related = &in_main[0]
        .related_information
        .as_ref()
        .expect("the real place")[0];
    assert_eq!(
        related.location,
        Location::new(lib.clone(), range(5, 19, 5, 21))
    );
    client.change(&lib, 3, vec![edit(range(5, 19, 5, 21), "k")]);
    assert_eq!(client.diagnostics(&lib, 3), vec![]);
    assert_eq!(client.diagnostics(&main, 1), vec![]);

    // Renaming the component's parameter renames its uses in the library and the override in the importer.
    let edit = client
        .request::<Rename>(lsp_types::RenameParams {
            text_document_position: position_params(&lib, find(LIB, "param k", 0, 6)),
            new_name: "stiffness".to_string(),
            work_done_progress_params: Default::default(),
        })
        .expect("rename answers")
        .expect("edits");
    let changes = edit.changes.expect("changes by document");
    assert_eq!(changes.len(), 2);
    assert_eq!(
        apply(LIB, &changes[&lib]),
        LIB.replace("param k =", "param stiffness =")
            .replace("1 / k;", "1 / stiffness;")
    );
    assert_eq!(
        apply(MAIN, &changes[&main]),
        MAIN.replace("pair(k = k_rig)", "pair(stiffness = k_rig)")
    );

    // Names that would not parse, and names already taken in the scope, are refused.
    for (name, why) in [
        ("bond", "reserved"),
        ("2k", "is not a name"),
        // A Greek letter, as papers write stiffness: the ASCII spelling is proposed.
        (
            "κ",
            "is not a name: a name is an ASCII letter or `_` followed by ASCII letters, digits and `_` (write `kappa`)",
        ),
        ("spring", "already declared"),
        // Ordinary names with a meaning of their own in a law block or a field: `k` renamed `q` would make
        // `C spring { e = q * q; }`-style laws read the element's own displacement.
        ("q", "has a meaning of its own"),
        ("f", "has a meaning of its own"),
        ("mass", "has a meaning of its own"),
    ] {
        let refused = client.request::<Rename>(lsp_types::RenameParams {
            text_document_position: position_params(&lib, find(LIB, "param k", 0, 6)),
            new_name: name.to_string(),
            work_done_progress_params: Default::default(),
        });
        let (code, message) = refused.expect_err("refused");
        assert_eq!(code, lsp_server::ErrorCode::InvalidParams as i32);
        assert!(message.contains(why), "{name}: {message}");
    }
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
fn formatting_returns_the_edits_of_bgc_fmt() {
    let mut client = Client::start();
    let doc = uri(&unsaved("messy.bg"));
    let messy = "model m {\ndomain rotational;\n   param k = 1 [N m/rad];\n\n\n  Se s = 1; 1 j; C c = 1/k;\n bond s -> j -> c;\n}\n";
    let tidy = "model m {\n    domain rotational;\n    param k = 1 [N m/rad];\n\n    Se s = 1;\n    1 j;\n    C c = 1 / k;\n    bond s -> j -> c;\n}\n";
    client.open(&doc, messy);
    client.diagnostics(&doc, 1);
    let format = |client: &mut Client| {
        client
            .request::<Formatting>(lsp_types::DocumentFormattingParams {
                text_document: TextDocumentIdentifier::new(doc.clone()),
                options: Default::default(),
                work_done_progress_params: Default::default(),
            })
            .expect("formatting answers")
    };
    let edits = format(&mut client).expect("edits");
    assert_eq!(apply(messy, &edits), tidy);
    // The first line is untouched, so the edit starts after it.
    assert_eq!(edits[0].range.start, Position::new(1, 0));
    // Formatted text needs no edit; text with syntax errors gets none.
    client.change(&doc, 2, vec![edit(range(0, 0, 99, 0), tidy)]);
    assert_eq!(format(&mut client), Some(vec![]));
    client.change(&doc, 3, vec![edit(range(0, 0, 99, 0), "model m {\n")]);
    assert_eq!(format(&mut client), None);
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
fn range_formatting_changes_only_the_selected_lines() {
    let mut client = Client::start();
    let doc = uri(&unsaved("messy_range.bg"));
    // Messy lines 1 and 3 between lines already in the canonical layout.
    let messy = "model m {\ndomain rotational;\n    param k = 1 [N m/rad];\n  Se s = 1; 1 j; C c = 1/k;\n    bond s -> j -> c;\n}\n";
    client.open(&doc, messy);
    client.diagnostics(&doc, 1);
    let format = |client: &mut Client, lines: lsp_types::Range| {
        client
            .request::<RangeFormatting>(lsp_types::DocumentRangeFormattingParams {
                text_document: TextDocumentIdentifier::new(doc.clone()),
                range: lines,
                options: Default::default(),
                work_done_progress_params: Default::default(),
            })
            .expect("range formatting answers")
    };
    // Line 3 (`Se s = 1; 1 j; C c = 1/k;`) alone: split and spaced; the messy line 1 stays as written.
    let edits = format(&mut client, range(3, 0, 3, 5)).expect("edits");
    assert_eq!(
        apply(messy, &edits),
        "model m {\ndomain rotational;\n    param k = 1 [N m/rad];\n    Se s = 1;\n    1 j;\n    C c = 1 / k;\n    bond s -> j -> c;\n}\n"
    );
    // Line 1 alone: the other way round.
    let edits = format(&mut client, range(1, 0, 1, 0)).expect("edits");
    assert_eq!(
        apply(messy, &edits),
        "model m {\n    domain rotational;\n    param k = 1 [N m/rad];\n  Se s = 1; 1 j; C c = 1/k;\n    bond s -> j -> c;\n}\n"
    );
    // Adjacent messy lines that the layout changes in place: only the selected one changes.
    let adjacent = "model m {\ndomain rotational;\nparam k = 1 [N m/rad];\nparam d=2 [N m s/rad];\n    Se s = 1;\n    1 j;\n    C c = 1 / k;\n    R r = d;\n    bond s -> j -> c, r;\n}\n";
    let second = uri(&unsaved("adjacent_range.bg"));
    client.open(&second, adjacent);
    client.diagnostics(&second, 1);
    let edits = client
        .request::<RangeFormatting>(lsp_types::DocumentRangeFormattingParams {
            text_document: TextDocumentIdentifier::new(second.clone()),
            range: range(3, 0, 3, 3),
            options: Default::default(),
            work_done_progress_params: Default::default(),
        })
        .expect("range formatting answers")
        .expect("edits");
    assert_eq!(
        apply(adjacent, &edits),
        adjacent.replace("param d=2 [N m s/rad];", "    param d = 2 [N m s/rad];")
    );
    // The whole file as the range gives what whole-document formatting gives.
    let all = format(&mut client, range(0, 0, 6, 0)).expect("edits");
    assert_eq!(
        apply(messy, &all),
        "model m {\n    domain rotational;\n    param k = 1 [N m/rad];\n    Se s = 1;\n    1 j;\n    C c = 1 / k;\n    bond s -> j -> c;\n}\n"
    );
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
fn completion_and_outline() {
    let mut client = Client::start();
    let lib = uri(&unsaved("lib.bg"));
    let main = uri(&unsaved("main.bg"));
    client.open(&lib, LIB);
    client.open(&main, MAIN);
    client.diagnostics(&main, 1);
    let complete = |client: &mut Client, at: Position| -> Vec<String> {
        let found = client
            .request::<Completion>(lsp_types::CompletionParams {
                text_document_position: position_params(&main, at),
                work_done_progress_params: Default::default(),
                partial_result_params: Default::default(),
                context: None,
            })
            .expect("completion answers");
        let Some(CompletionResponse::Array(items)) = found else {
            panic!("items")
        };
        let mut labels: Vec<String> = items.into_iter().map(|i| i.label).collect();
        labels.sort();
        labels
    };
    // After `pair.`: what damper_pair declares that a bond or `e(...)` can name.
    assert_eq!(
        complete(&mut client, find(MAIN, "e(pair.spring)", 0, 7)),
        ["a", "b", "damper", "j", "rel", "spring"]
    );
    // Inside a unit's brackets: unit symbols.
    let units = complete(&mut client, find(MAIN, "[N m]", 0, 1));
    // Only what a file may write: not `Ω`, which `BG0104` refuses (its help says `Ohm`).
    assert!(units.iter().all(|l| l.is_ascii()), "{units:?}");
    for u in ["N", "m", "rad", "rpm", "Ohm", "kg"] {
        assert!(units.iter().any(|l| l == u), "{u} in {units:?}");
    }
    // In an expression: the model's names and the functions.
    let names = complete(&mut client, find(MAIN, "= tau;", 0, 2));
    for n in ["k_rig", "tau", "torque", "pair", "sin", "atan2", "t"] {
        assert!(names.iter().any(|l| l == n), "{n} in {names:?}");
    }
    let outline = client
        .request::<DocumentSymbolRequest>(lsp_types::DocumentSymbolParams {
            text_document: TextDocumentIdentifier::new(main.clone()),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .expect("outline answers");
    let Some(DocumentSymbolResponse::Nested(symbols)) = outline else {
        panic!("nested symbols")
    };
    assert_eq!(symbols.len(), 1);
    assert_eq!(symbols[0].name, "rig");
    let children: Vec<(String, Option<String>)> = symbols[0]
        .children
        .iter()
        .flatten()
        .map(|c| (c.name.clone(), c.detail.clone()))
        .collect();
    let expected = [
        ("k_rig", "parameter"),
        ("tau", "input"),
        ("drive", "Se"),
        ("j1", "1"),
        ("mass", "I"),
        ("pair", "damper_pair instance"),
        ("ground", "Sf"),
        ("torque", "output"),
    ];
    assert_eq!(
        children,
        expected.map(|(n, d)| (n.to_string(), Some(d.to_string())))
    );
    assert_eq!(symbols[0].range, range(2, 0, 14, 1));
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
fn bad_requests_are_answered_with_errors_and_the_session_goes_on() {
    let mut client = Client::start();
    let doc = uri(&unsaved("m.bg"));
    let text = "model m {\n    domain rotational;\n    param k = 1 [N m/rad];\n}\n";
    client.open(&doc, text);
    client.diagnostics(&doc, 1);
    let wrong = client.raw_request(
        "textDocument/hover",
        serde_json::json!({ "position": "nowhere" }),
    );
    assert_eq!(
        wrong.error.map(|e| e.code),
        Some(lsp_server::ErrorCode::InvalidParams as i32)
    );
    let unknown = client.raw_request("bgc/noSuchRequest", serde_json::Value::Null);
    assert_eq!(
        unknown.error.map(|e| e.code),
        Some(lsp_server::ErrorCode::MethodNotFound as i32)
    );
    // A hover on a document the server does not know has nothing to show.
    let other = uri(&unsaved("never_opened.bg"));
    let nothing = client.request::<HoverRequest>(lsp_types::HoverParams {
        text_document_position_params: position_params(&other, Position::new(0, 0)),
        work_done_progress_params: Default::default(),
    });
    assert_eq!(nothing, Ok(None));
    assert!(
        hover_text(&mut client, &doc, Position::new(2, 11)).contains("parameter `k` of model `m`")
    );
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

const DERIVATIVE: &str = "model d {
    domain translational;
    param m = 1 [kg];
    input v_in [m/s];
    Sf src = v_in;
    I m0 = m;
    bond src -> m0;
    output force [N] = e(m0);
}
";

fn codes(found: &[lsp_types::Diagnostic]) -> Vec<String> {
    found.iter().map(code).collect()
}

#[test]
fn equation_stage_errors_are_published_which_bgc_check_leaves_out() {
    // A flow source drives an inertia: its effort is m dv/dt, so the output `force` needs the derivative of the
    // input, which the equations stage refuses (BG0602); `bgc check` stops at causality (BG0510).
    let mut client = Client::start();
    let doc = uri(&unsaved("derivative.bg"));
    client.open(&doc, DERIVATIVE);
    let found = client.diagnostics(&doc, 1);
    assert_eq!(codes(&found), ["BG0510", "BG0602"]);
    assert_eq!(found[1].severity, Some(DiagnosticSeverity::ERROR));
    assert!(
        found[1]
            .message
            .starts_with("output `force` needs the time derivative of input `v_in`")
    );
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}

#[test]
fn large_documents_get_the_front_end_first_and_the_equations_after() {
    // Every document counts as large here: the front end's findings come first, the equation stage's with the
    // second publication of the same version.
    let options = bgc::lsp::Options {
        background_above: 1,
        ..bgc::lsp::Options::default()
    };
    let mut client = Client::start_with(options);
    let doc = uri(&unsaved("derivative.bg"));
    client.open(&doc, DERIVATIVE);
    assert_eq!(codes(&client.diagnostics(&doc, 1)), ["BG0510"]);
    assert_eq!(codes(&client.diagnostics(&doc, 1)), ["BG0510", "BG0602"]);
    // Requests then see the equations: the inertia's hover shows its intermediate.
    let m0 = hover_text(&mut client, &doc, find(DERIVATIVE, "I m0", 0, 3));
    assert!(
        m0.contains("- derivative causality (no state of its own)"),
        "{m0}"
    );
    assert!(m0.contains("- `e_m0 = d/dt "), "{m0}");
    // A change: again the front end first, then everything.
    let p = find(DERIVATIVE, "param m = 1", 0, 10);
    client.change(
        &doc,
        2,
        vec![edit(
            range(p.line, p.character, p.line, p.character + 1),
            "2",
        )],
    );
    assert_eq!(codes(&client.diagnostics(&doc, 2)), ["BG0510"]);
    assert_eq!(codes(&client.diagnostics(&doc, 2)), ["BG0510", "BG0602"]);
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
}
