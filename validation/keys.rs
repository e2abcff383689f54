//! The reference of every scene-file and sweep-file key, `docs/keys.md`, generated from the
//! schema of the files' own types (schemars reads their serde attributes and doc comments), and
//! the JSON schemas beside it (`docs/scene.schema.json`, `docs/sweep.schema.json`, for editors
//! that validate TOML against one). The test fails when
//! either file is not what the code generates: a key added, renamed or documented differently
//! without the reference following. To regenerate both after such a change:
//! `GRAINCHAIN_BLESS=1 cargo test --test validation keys::`, then review the diff.

use serde_json::{Map, Value};
use std::fmt::Write as _;
use std::path::Path;

/// A file whose keys the reference lists: its heading, what it is, and its schema.
struct Schema {
    name: &'static str,
    what: &'static str,
    schema: Value,
    json: &'static str,
}

fn schemas() -> Vec<Schema> {
    vec![
        Schema {
            name: "Scene files",
            what: "a scene (`grainchain run`, `check`; `scenes/`)",
            schema: serde_json::to_value(schemars::schema_for!(grainchain_engine::file::SceneFile))
                .unwrap(),
            json: "docs/scene.schema.json",
        },
        Schema {
            name: "Sweep files",
            what: "a study (`grainchain study`; `studies/`)",
            schema: serde_json::to_value(schemars::schema_for!(grainchain::study::Sweep)).unwrap(),
            json: "docs/sweep.schema.json",
        },
        Schema {
            name: "Design files",
            what: "a protector design search (`grainchain design`; `designs/`)",
            schema: serde_json::to_value(schemars::schema_for!(
                grainchain::design::file::DesignFile
            ))
            .unwrap(),
            json: "docs/design.schema.json",
        },
    ]
}

/// Every key name of the scene and sweep schemas, in any table (the tag keys of tagged tables
/// too).
pub(crate) fn key_names() -> std::collections::BTreeSet<String> {
    fn collect(v: &Value, out: &mut std::collections::BTreeSet<String>) {
        match v {
            Value::Object(m) => {
                if let Some(Value::Object(props)) = m.get("properties") {
                    out.extend(props.keys().cloned());
                }
                m.values().for_each(|x| collect(x, out));
            }
            Value::Array(a) => a.iter().for_each(|x| collect(x, out)),
            _ => {}
        }
    }
    let mut out = std::collections::BTreeSet::new();
    for sc in schemas() {
        collect(&sc.schema, &mut out);
    }
    out
}

/// One row: the key's dotted path, its type, whether it must be given (or its default), and
/// its doc comment.
struct Row {
    key: String,
    kind: String,
    need: String,
    doc: String,
}

/// The definition a `$ref` names.
fn resolve<'a>(defs: &'a Map<String, Value>, v: &'a Value) -> &'a Value {
    match v.get("$ref").and_then(Value::as_str) {
        Some(r) => &defs[r.trim_start_matches("#/$defs/")],
        None => v,
    }
}

/// The schema without its `null` alternative (an `Option`), and whether there was one.
fn strip_null<'a>(defs: &'a Map<String, Value>, v: &'a Value) -> (&'a Value, bool) {
    if let Some(any) = v.get("anyOf").and_then(Value::as_array) {
        let rest: Vec<&Value> = any
            .iter()
            .filter(|a| a.get("type") != Some(&Value::from("null")))
            .collect();
        if rest.len() == 1 && any.len() == 2 {
            return (resolve(defs, rest[0]), true);
        }
    }
    (resolve(defs, v), false)
}

/// A type in words: `number`, `integer >= 0`, `string`, `true/false`, `table`, `array of ..`,
/// one of a list of names.
fn kind(defs: &Map<String, Value>, v: &Value) -> String {
    let (v, _) = strip_null(defs, v);
    if let Some(names) = names(v) {
        return format!("one of {}", names.join(", "));
    }
    if v.get("oneOf").is_some() {
        return "table (one of the forms below)".into();
    }
    let types: Vec<String> = match v.get("type") {
        Some(Value::String(t)) => vec![t.clone()],
        Some(Value::Array(a)) => a
            .iter()
            .filter_map(Value::as_str)
            .filter(|t| *t != "null")
            .map(String::from)
            .collect(),
        _ => vec![],
    };
    let t = types.first().map(String::as_str).unwrap_or("value");
    match t {
        "array" => match v.get("items") {
            Some(items) => format!("array of {}", kind(defs, items)),
            None => "array".into(),
        },
        "object" => "table".into(),
        "boolean" => "true or false".into(),
        "integer" if v.get("minimum") == Some(&Value::from(0)) => "integer >= 0".into(),
        t => t.into(),
    }
}

/// The names of an enum of plain names (`"verlet" | "blanes-moan4" | ..`), quoted.
fn names(v: &Value) -> Option<Vec<String>> {
    let quote = |s: &str| format!("`\"{s}\"`");
    if let Some(e) = v.get("enum").and_then(Value::as_array) {
        return Some(e.iter().filter_map(Value::as_str).map(quote).collect());
    }
    let one = v.get("oneOf").and_then(Value::as_array)?;
    one.iter()
        .map(|o| o.get("const").and_then(Value::as_str).map(quote))
        .collect()
}

/// The doc comment, on one line (a table cell), its intra-doc links as plain code
/// (`crate::run::Horizon` as `Horizon`).
fn doc(v: &Value) -> String {
    let mut text = v
        .get("description")
        .and_then(Value::as_str)
        .unwrap_or("")
        .to_string();
    while let Some(i) = text.find("crate::") {
        let end = text[i..].find('`').map_or(text.len(), |e| i + e);
        let last = text[i..end].rfind("::").map_or(i, |l| i + l + 2);
        text.replace_range(i..last, "");
    }
    text.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .replace("[`", "`")
        .replace("`]", "`")
        .replace('|', "\\|")
}

/// The rows of the table `v` at path `prefix`, and of every table inside it.
fn walk(defs: &Map<String, Value>, prefix: &str, v: &Value, rows: &mut Vec<Row>) {
    let v = resolve(defs, v);
    // A table of several forms, told apart by a tag key (`kind = "wall"`, `medium = "long"`).
    if let Some(forms) = v.get("oneOf").and_then(Value::as_array) {
        if names(v).is_none() {
            let tags: Vec<(&String, &str)> = forms
                .iter()
                .filter_map(|f| f.get("properties").and_then(Value::as_object))
                .filter_map(|p| {
                    p.iter()
                        .find_map(|(k, s)| s.get("const").and_then(Value::as_str).map(|c| (k, c)))
                })
                .collect();
            if let Some((tag, _)) = tags.first() {
                let values: Vec<String> = tags.iter().map(|(_, c)| format!("`\"{c}\"`")).collect();
                rows.push(Row {
                    key: format!("{prefix}.{tag}"),
                    kind: format!("one of {}", values.join(", ")),
                    need: "required".into(),
                    doc: "which form the table takes (below)".into(),
                });
            }
            for form in forms {
                let props = form.get("properties").and_then(Value::as_object);
                let tag = props.and_then(|p| {
                    p.iter()
                        .find_map(|(k, s)| s.get("const").and_then(Value::as_str).map(|c| (k, c)))
                });
                let label = match tag {
                    Some((k, c)) => format!("{prefix} ({k} = \"{c}\")"),
                    None => prefix.to_string(),
                };
                rows.push(Row {
                    key: label.clone(),
                    kind: "form".into(),
                    need: String::new(),
                    doc: doc(form),
                });
                table(defs, &label, form, rows, tag.map(|(k, _)| k.as_str()));
            }
            return;
        }
    }
    table(defs, prefix, v, rows, None);
}

/// The keys of one table (its properties), `skip` a form's tag key, already in the label.
fn table(
    defs: &Map<String, Value>,
    prefix: &str,
    v: &Value,
    rows: &mut Vec<Row>,
    skip: Option<&str>,
) {
    let Some(props) = v.get("properties").and_then(Value::as_object) else {
        return;
    };
    let required: Vec<&str> = v
        .get("required")
        .and_then(Value::as_array)
        .map(|r| r.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    for (name, p) in props {
        if Some(name.as_str()) == skip {
            continue;
        }
        let key = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}.{name}")
        };
        let (inner, _) = strip_null(defs, p);
        let need = if required.contains(&name.as_str()) {
            "required".to_string()
        } else {
            match p.get("default") {
                Some(Value::Null) | None => "optional".into(),
                Some(d) => format!("default {d}"),
            }
        };
        let own = doc(p);
        rows.push(Row {
            key: key.clone(),
            kind: kind(defs, p),
            need,
            doc: if own.is_empty() { doc(inner) } else { own },
        });
        let is_array = inner.get("type") == Some(&Value::from("array"));
        if is_array {
            if let Some(items) = inner.get("items") {
                walk(defs, &format!("{key}[]"), items, rows);
            }
        } else if inner.get("properties").is_some() || inner.get("oneOf").is_some() {
            walk(defs, &key, inner, rows);
        }
    }
}

/// `docs/keys.md` as the code makes it.
fn reference(schemas: &[Schema]) -> String {
    let mut s = String::from(
        "# Key reference\n\n\
         Generated from the code by `cargo test` (`validation/keys.rs`, from the schema of the \
         files' own types and their doc comments); do not edit by hand. After changing a key, \
         regenerate with `GRAINCHAIN_BLESS=1 cargo test --test validation keys::` and review \
         the diff. Every table refuses keys it does not list. Grain numbers are the printed \
         ones (1-based; a left striker is 0).\n",
    );
    for sc in schemas {
        let defs = sc.schema["$defs"].as_object().cloned().unwrap_or_default();
        let mut rows = Vec::new();
        walk(&defs, "", &sc.schema, &mut rows);
        write!(
            s,
            "\n## {}\n\n{}: {} keys. JSON schema: [`{}`]({}).\n\n| key | type | given | what it is |\n|---|---|---|---|\n",
            sc.name,
            sc.what,
            rows.iter().filter(|r| r.kind != "form").count(),
            sc.json,
            Path::new(sc.json).file_name().unwrap().to_string_lossy()
        )
        .unwrap();
        for r in rows {
            writeln!(s, "| `{}` | {} | {} | {} |", r.key, r.kind, r.need, r.doc).unwrap();
        }
    }
    s
}

/// Compare `path` with `want`; with `GRAINCHAIN_BLESS=1` write it instead.
fn check(path: &str, want: &str, problems: &mut Vec<String>) {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    if std::env::var_os("GRAINCHAIN_BLESS").is_some() {
        std::fs::write(&file, want).unwrap();
        return;
    }
    let have = std::fs::read_to_string(&file).unwrap_or_default();
    if have != want {
        let line = have
            .lines()
            .zip(want.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(have.lines().count().min(want.lines().count()));
        problems.push(format!(
            "{path} is stale (first difference at line {}): regenerate it with \
             `GRAINCHAIN_BLESS=1 cargo test --test validation keys::` and review the diff",
            line + 1
        ));
    }
}

#[test]
fn the_key_reference_is_what_the_code_generates() {
    let schemas = schemas();
    let mut problems = Vec::new();
    check("docs/keys.md", &reference(&schemas), &mut problems);
    for sc in &schemas {
        let json = serde_json::to_string_pretty(&sc.schema).unwrap() + "\n";
        check(sc.json, &json, &mut problems);
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The generator lists what it should: every key of a shipped scene and sweep file appears in
/// the reference of its kind (the keys read from the TOML itself, not from the schema), so a
/// walk that missed a nested table or an array of tables would fail here.
#[test]
fn every_key_of_the_shipped_scenes_and_sweeps_is_in_the_reference() {
    let mut missing = Vec::new();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (dir, schema) in [("scenes", 0), ("scenes/containers", 0), ("studies", 1)] {
        let text = reference(&schemas()[schema..=schema]);
        let listed: Vec<&str> = text
            .lines()
            .filter_map(|l| l.strip_prefix("| `"))
            .filter_map(|l| l.split('`').next())
            .collect();
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_none_or(|x| x != "toml") {
                continue;
            }
            let v: toml::Value = toml::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
            let mut keys = Vec::new();
            toml_keys("", &v, &mut keys);
            for k in keys {
                // A form's keys are listed under the form's label (`chain.left (kind = "wall").p`).
                let found = listed.iter().any(|l| *l == k || strip_forms(l) == k);
                if !found {
                    missing.push(format!("{}: {k}", p.display()));
                }
            }
        }
    }
    assert!(
        missing.is_empty(),
        "keys of shipped scenes not in docs/keys.md:\n{}",
        missing.join("\n")
    );
}

/// `a (kind = "wall").p` -> `a.p`: a key inside a form without its form.
fn strip_forms(l: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in l.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out.replace(" .", ".").trim().to_string()
}

/// Every dotted key path of a TOML value (arrays of tables as `name[]`).
fn toml_keys(prefix: &str, v: &toml::Value, out: &mut Vec<String>) {
    if let toml::Value::Table(t) = v {
        for (k, x) in t {
            let key = if prefix.is_empty() {
                k.clone()
            } else {
                format!("{prefix}.{k}")
            };
            out.push(key.clone());
            match x {
                toml::Value::Table(_) => toml_keys(&key, x, out),
                toml::Value::Array(a) if a.iter().all(|i| i.is_table()) => {
                    for i in a {
                        toml_keys(&format!("{key}[]"), i, out);
                    }
                }
                _ => {}
            }
        }
    }
}
