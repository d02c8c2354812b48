//! Errors inside tagged tables pointed at their field's line.
//!
//! `[materials.X]` (tagged by `model`) and `[[light]]` (tagged by `type`)
//! are read through serde's internally tagged enums, which buffer the table
//! before choosing the variant: a wrong value inside then comes back
//! without its field or position, and toml reports it at the table's
//! header. Here the table is read again without one field at a time; the
//! field whose absence changes the error is the one at fault, and the
//! message is given again at that field's line, naming it.

use serde::de::DeserializeOwned;
use serde_path_to_error::Segment;
use toml::de::{DeTable, DeValue};

use super::desc::LightDesc;
use crate::material_desc::MaterialDesc;

/// The message for an error that serde placed at `path`, given at its
/// field's line and naming it, when `path` is a tagged table and one field
/// is at fault; `None` otherwise (the caller keeps toml's message). A
/// missing field belongs at the table's header, where toml puts it.
pub(super) fn locate(text: &str, path: &serde_path_to_error::Path) -> Option<String> {
    let segments: Vec<&Segment> = path.iter().collect();
    let doc: toml::Table = text.parse().ok()?;
    let spans = DeTable::parse(text).ok()?;
    let (value, de, shown) = match segments.as_slice() {
        [Segment::Map { key: top }, Segment::Map { key }] if top == "materials" => (
            doc.get("materials")?.get(key.as_str())?,
            table_entry(spans.get_ref(), "materials")?
                .as_table()
                .and_then(|t| table_entry(t, key))?,
            format!("materials.{key}"),
        ),
        [Segment::Map { key: top }, Segment::Seq { index }] if top == "light" => (
            doc.get("light")?.get(*index)?,
            table_entry(spans.get_ref(), "light")?
                .as_array()?
                .get(*index)?
                .get_ref(),
            format!("light[{index}]"),
        ),
        _ => return None,
    };
    let table = value.as_table()?;
    let (field, why) = if shown.starts_with("light") {
        culprit::<LightDesc>(table, "type")?
    } else {
        culprit::<MaterialDesc>(table, "model")?
    };
    let start = key_span(de.as_table()?, &field)?;
    Some(at_line(
        text,
        start,
        &format!("{why} (in `{shown}.{field}`)"),
    ))
}

/// The value under `key` in a parsed table with spans.
fn table_entry<'a, 'i>(table: &'a DeTable<'i>, key: &str) -> Option<&'a DeValue<'i>> {
    table
        .iter()
        .find(|(k, _)| &**k.get_ref() == key)
        .map(|(_, v)| v.get_ref())
}

/// Where `key` starts in the text (its byte offset).
fn key_span(table: &DeTable, key: &str) -> Option<usize> {
    table
        .iter()
        .find(|(k, _)| &**k.get_ref() == key)
        .map(|(k, _)| k.span().start)
}

/// The field of `table` that reading it as `T` stumbles on, with the
/// error: the one without which the read fails differently (or not at
/// all). With several bad fields, dropping one that is not reported leaves
/// the error as it was. The `tag` field is at fault only for an unknown
/// variant (without it every read fails on the tag).
fn culprit<T: DeserializeOwned>(table: &toml::Table, tag: &str) -> Option<(String, String)> {
    let read = |t: &toml::Table| {
        toml::Value::Table(t.clone())
            .try_into::<T>()
            .err()
            .map(|e| e.message().trim_end().to_string())
    };
    let base = read(table)?;
    if base.contains("missing field") {
        return None;
    }
    let tag_at_fault = base.contains("variant");
    let field = table.keys().find(|k| {
        if k.as_str() == tag && !tag_at_fault {
            return false;
        }
        let mut without = table.clone();
        without.remove(k.as_str());
        read(&without).as_ref() != Some(&base)
    })?;
    Some((field.clone(), base))
}

/// `message` in toml's layout, at byte `offset` of `text`: the line and
/// column, the line quoted with a caret under the field.
fn at_line(text: &str, offset: usize, message: &str) -> String {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    let quoted = text[line_start..].lines().next().unwrap_or("");
    let quoted = crate::validate::truncate_echo(quoted, 200);
    let pad = " ".repeat(line.to_string().len());
    format!(
        "TOML parse error at line {line}, column {column}\n{pad} |\n{line} | {quoted}\n{pad} | {}^\n{message}",
        " ".repeat(column - 1)
    )
}
