//! One table of the scene file as a parameter dictionary: typed getters that
//! remember every key they were asked for, and one generic unread-key check
//! ([`Params::finish`], after pbrt-v4's `ParameterDictionary::ReportUnused`).
//!
//! Every value of the format goes through these getters, so each rule holds
//! everywhere at once: numbers are finite f32, a fixed-length array has exactly
//! its length (one element more or less is an error naming the key and the
//! length), a choice lists its valid values, and a key that the table's reader
//! never asked for is an error listing the keys it did ask for.

use super::locate::{Ctx, KeyPath};
use std::cell::RefCell;
use toml::Value;

/// `a`, `a` or `b`, one of `a`, `b`, `c` — serde's phrasing, which the messages
/// (and their tests) have always used.
pub(super) fn expected_one_of(names: &[&str]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    match quoted.as_slice() {
        [] => "nothing".into(),
        [one] => one.clone(),
        [a, b] => format!("{a} or {b}"),
        _ => format!("one of {}", quoted.join(", ")),
    }
}

/// `a`, `b`, `c`: a plain list of names.
pub(super) fn list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// How a TOML value is named in "got …" messages.
fn describe(v: &Value) -> String {
    let text = match v {
        // Debug writes 1e-46 where Display writes 47 digits.
        Value::Float(f) => format!("{f:?}"),
        other => other.to_string(),
    };
    let short = if text.chars().count() > 40 {
        format!("{}…", text.chars().take(40).collect::<String>())
    } else {
        text
    };
    format!("{} {short}", v.type_str())
}

/// A number of the format: an integer or a float, as f32, finite.
pub(super) fn number(ctx: &Ctx, at: &KeyPath, v: &Value) -> crate::Result<f32> {
    let x = match v {
        Value::Integer(i) => *i as f32,
        Value::Float(f) => *f as f32,
        other => {
            return Err(ctx.err(
                at,
                format!("expected f32 (a number), got {}", describe(other)),
            ))
        }
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(ctx.err(at, format!("expected a finite number, got {v}")))
    }
}

/// Exactly `N` numbers.
pub(super) fn numbers<const N: usize>(
    ctx: &Ctx,
    at: &KeyPath,
    v: &Value,
) -> crate::Result<[f32; N]> {
    let a = fixed_array(ctx, at, v, N)?;
    let mut out = [0.0; N];
    for (i, (o, x)) in out.iter_mut().zip(a).enumerate() {
        *o = number(ctx, &at.index(i), x).map_err(|_| {
            ctx.err(
                at,
                format!(
                    "expected {N} finite numbers, got {}",
                    describe(v).trim_start_matches("array ")
                ),
            )
        })?;
    }
    Ok(out)
}

/// An array of exactly `n` elements.
fn fixed_array<'v>(ctx: &Ctx, at: &KeyPath, v: &'v Value, n: usize) -> crate::Result<&'v [Value]> {
    match v.as_array() {
        Some(a) if a.len() == n => Ok(a),
        Some(a) => Err(ctx.err(
            at,
            format!(
                "expected an array of length {n}, got an array of length {}",
                a.len()
            ),
        )),
        None => Err(ctx.err(
            at,
            format!("expected an array of length {n}, got {}", describe(v)),
        )),
    }
}

fn u32_of(ctx: &Ctx, at: &KeyPath, v: &Value) -> crate::Result<u32> {
    match v {
        Value::Integer(i) => u32::try_from(*i).map_err(|_| {
            ctx.err(
                at,
                format!("expected u32 (an integer from 0 to {}), got {i}", u32::MAX),
            )
        }),
        other => Err(ctx.err(
            at,
            format!("expected u32 (an integer), got {}", describe(other)),
        )),
    }
}

/// One table of the file and the keys its reader has asked for.
pub(super) struct Params<'a> {
    pub(super) ctx: &'a Ctx<'a>,
    pub(super) at: KeyPath,
    table: &'a toml::Table,
    /// Every key looked up, present or not, in lookup order: the valid keys.
    asked: RefCell<Vec<&'static str>>,
    /// The table's `type`, once read: "does not apply to type = …" messages.
    kind: RefCell<Option<&'static str>>,
}

impl<'a> Params<'a> {
    pub(super) fn new(ctx: &'a Ctx<'a>, at: KeyPath, table: &'a toml::Table) -> Self {
        Self {
            ctx,
            at,
            table,
            asked: RefCell::new(Vec::new()),
            kind: RefCell::new(None),
        }
    }

    /// The value at `key`, marking the key as read.
    pub(super) fn get(&self, key: &'static str) -> Option<&'a Value> {
        let mut asked = self.asked.borrow_mut();
        if !asked.contains(&key) {
            asked.push(key);
        }
        self.table.get(key)
    }

    pub(super) fn path(&self, key: &str) -> KeyPath {
        self.at.key(key)
    }

    pub(super) fn err(&self, key: Option<&str>, message: impl Into<String>) -> crate::Error {
        match key {
            Some(k) => self.ctx.err(&self.at.key(k), message),
            None => self.ctx.err(&self.at, message),
        }
    }

    fn read<T>(
        &self,
        key: &'static str,
        f: impl FnOnce(&Ctx, &KeyPath, &'a Value) -> crate::Result<T>,
    ) -> crate::Result<Option<T>> {
        self.get(key)
            .map(|v| f(self.ctx, &self.at.key(key), v))
            .transpose()
    }

    pub(super) fn f32(&self, key: &'static str) -> crate::Result<Option<f32>> {
        self.read(key, number)
    }

    pub(super) fn f32s<const N: usize>(
        &self,
        key: &'static str,
    ) -> crate::Result<Option<[f32; N]>> {
        self.read(key, numbers::<N>)
    }

    pub(super) fn u32(&self, key: &'static str) -> crate::Result<Option<u32>> {
        self.read(key, u32_of)
    }

    /// Exactly two unsigned integers (`resolution`).
    pub(super) fn u32_pair(&self, key: &'static str) -> crate::Result<Option<[u32; 2]>> {
        self.read(key, |ctx, at, v| {
            let a = fixed_array(ctx, at, v, 2)?;
            Ok([
                u32_of(ctx, &at.index(0), &a[0])?,
                u32_of(ctx, &at.index(1), &a[1])?,
            ])
        })
    }

    pub(super) fn bool(&self, key: &'static str) -> crate::Result<Option<bool>> {
        self.read(key, |ctx, at, v| {
            v.as_bool()
                .ok_or_else(|| ctx.err(at, format!("expected true or false, got {}", describe(v))))
        })
    }

    pub(super) fn string(&self, key: &'static str) -> crate::Result<Option<&'a str>> {
        self.read(key, |ctx, at, v| {
            v.as_str()
                .ok_or_else(|| ctx.err(at, format!("expected a string, got {}", describe(v))))
        })
    }

    /// A string naming one of `choices`: its name and value.
    fn named_choice<T: Copy>(
        &self,
        key: &'static str,
        choices: &[(&'static str, T)],
    ) -> crate::Result<Option<(&'static str, T)>> {
        let Some(s) = self.string(key)? else {
            return Ok(None);
        };
        match choices.iter().find(|c| c.0 == s) {
            Some(&c) => Ok(Some(c)),
            None => {
                let names: Vec<&str> = choices.iter().map(|c| c.0).collect();
                Err(self.err(
                    Some(key),
                    format!(
                        "unknown variant `{s}`, expected {}",
                        expected_one_of(&names)
                    ),
                ))
            }
        }
    }

    /// A string naming one of `choices`.
    pub(super) fn choice<T: Copy>(
        &self,
        key: &'static str,
        choices: &[(&'static str, T)],
    ) -> crate::Result<Option<T>> {
        Ok(self.named_choice(key, choices)?.map(|c| c.1))
    }

    /// The required `type` key: one of `choices`. Later messages name it.
    pub(super) fn kind<T: Copy>(&self, choices: &[(&'static str, T)]) -> crate::Result<T> {
        let Some((name, t)) = self.named_choice("type", choices)? else {
            let names: Vec<&str> = choices.iter().map(|c| c.0).collect();
            return Err(self.err(
                None,
                format!("missing field `type`: expected {}", expected_one_of(&names)),
            ));
        };
        *self.kind.borrow_mut() = Some(name);
        Ok(t)
    }

    /// The `type` read by [`Params::kind`] (for messages).
    pub(super) fn kind_name(&self) -> &'static str {
        self.kind.borrow().unwrap_or("")
    }

    /// A required key's value, or an error saying that this type needs it.
    pub(super) fn need<T>(&self, key: &str, v: Option<T>) -> crate::Result<T> {
        v.ok_or_else(|| match self.kind.borrow().as_ref() {
            Some(kind) => self.err(None, format!("type = \"{kind}\" needs `{key}`")),
            None => self.err(None, format!("missing field `{key}`")),
        })
    }

    /// A sub-table (inline or not).
    pub(super) fn table(&self, key: &'static str) -> crate::Result<Option<Params<'a>>> {
        let ctx = self.ctx;
        self.get(key)
            .map(|v| match v {
                Value::Table(t) => Ok(Params::new(ctx, self.at.key(key), t)),
                other => Err(self.err(
                    Some(key),
                    format!("expected a table, got {}", describe(other)),
                )),
            })
            .transpose()
    }

    /// An array (of any length); elements come with their key paths.
    pub(super) fn array(
        &self,
        key: &'static str,
    ) -> crate::Result<Option<Vec<(KeyPath, &'a Value)>>> {
        self.read(key, |ctx, at, v| match v {
            Value::Array(a) => Ok(a
                .iter()
                .enumerate()
                .map(|(i, x)| (at.index(i), x))
                .collect()),
            other => Err(ctx.err(at, format!("expected an array, got {}", describe(other)))),
        })
    }

    /// An array of tables (`[[shapes]]`, `terms = [{ … }]`).
    pub(super) fn tables(&self, key: &'static str) -> crate::Result<Option<Vec<Params<'a>>>> {
        let Some(items) = self.array(key)? else {
            return Ok(None);
        };
        items
            .into_iter()
            .map(|(at, v)| match v {
                Value::Table(t) => Ok(Params::new(self.ctx, at, t)),
                other => Err(self
                    .ctx
                    .err(&at, format!("expected a table, got {}", describe(other)))),
            })
            .collect::<crate::Result<Vec<_>>>()
            .map(Some)
    }

    /// A table of named tables (`[materials.NAME]`), sorted by name.
    pub(super) fn named_tables(
        &self,
        key: &'static str,
    ) -> crate::Result<Vec<(&'a str, Params<'a>)>> {
        let Some(outer) = self.table(key)? else {
            return Ok(Vec::new());
        };
        let mut out = Vec::with_capacity(outer.table.len());
        for (name, v) in outer.table {
            let at = outer.at.key(name);
            match v {
                Value::Table(t) => out.push((name.as_str(), Params::new(self.ctx, at, t))),
                other => {
                    return Err(self.ctx.err(
                        &at,
                        format!("expected a table [{key}.{name}], got {}", describe(other)),
                    ))
                }
            }
        }
        out.sort_by(|a, b| a.0.cmp(b.0));
        Ok(out)
    }

    /// The generic unread-key check: a key present in the table that no getter
    /// asked for is an error listing the keys that were asked for (`type`
    /// excepted). Call it once all of the table's keys have been read.
    pub(super) fn finish(&self) -> crate::Result<()> {
        let asked = self.asked.borrow();
        let Some(unread) = self.table.keys().find(|k| !asked.contains(&k.as_str())) else {
            return Ok(());
        };
        let valid: Vec<&str> = asked.iter().copied().filter(|k| *k != "type").collect();
        let message = match self.kind.borrow().as_ref() {
            Some(kind) => format!(
                "`{unread}` does not apply to type = \"{kind}\"; its keys are {}",
                list(&valid)
            ),
            None => format!(
                "unknown field `{unread}`, expected {}",
                expected_one_of(&valid)
            ),
        };
        Err(self.ctx.key_err(&self.at.key(unread), message))
    }
}
