//! Typing a written value against one field type: its numbers, bools and strings into a
//! [`Value`], with the message for whatever does not fit (a word where a number goes, arity,
//! integers, colours, a rotation about no axis, an SFImage's shape). Nodes and templates are
//! the lowerer's: it calls [`Typing::literal`] for the rest. The catalogue types its defaults
//! with the same code, so a default can never disagree with its type.

use std::borrow::Cow;

use regatta_parser::syntax::{self, Atom, Items};
use regatta_parser::{Diagnostic, Span};

use crate::value::{BaseType, FieldType, Image, Value};

/// What a written value typed to: a value, or (for SFNode and MFNode) the atoms that the
/// lowerer makes nodes of.
pub(crate) enum Literal<'v> {
    Value(Value),
    Nodes(&'v [Atom]),
}

/// One value to type, and what its messages need.
pub(crate) struct Typing<'a> {
    /// The text of the file the value is written in (messages quote it).
    pub text: &'a str,
    pub ty: FieldType,
    /// The field's name, for messages.
    pub field_name: &'a str,
    /// Strict mode: a rotation about the axis 0 0 0 is an error, not a warning.
    pub strict: bool,
    /// Why a string is not one of the field's allowed values (`None`: it is).
    pub disallowed: &'a dyn Fn(&syntax::StringLit) -> Option<Diagnostic>,
}

/// `SFVec3f [1 2 3]`: a single value written as a bracketed list.
pub(crate) fn bracketed(value: &syntax::Value, ty: FieldType) -> Option<Diagnostic> {
    (!ty.multi && value.bracketed).then(|| {
        Diagnostic::error(
            value.span,
            format!("{ty} takes a single value, not a bracketed list"),
        )
        .with_code("type")
    })
}

impl Typing<'_> {
    /// Types a value (its templates already evaluated): `None` after pushing the problem to
    /// `problems`, which may also receive warnings for a value that types.
    pub fn literal<'v>(
        &self,
        value: &'v syntax::Value,
        problems: &mut Vec<Diagnostic>,
    ) -> Option<Literal<'v>> {
        let (ty, field_name) = (self.ty, self.field_name);
        let base = ty.base;
        if base.is_numeric() {
            let numbers: Cow<[f64]> = match &value.items {
                Items::Numbers(list) => Cow::Borrowed(&list.values),
                Items::Atoms(atoms) => {
                    let mut numbers = Vec::with_capacity(atoms.len());
                    for atom in atoms {
                        match atom {
                            Atom::Number(n) => numbers.push(n.value),
                            other => {
                                let text = &self.text[other.span().range()];
                                problems.push(
                                    Diagnostic::error(
                                        other.span(),
                                        format!(
                                            "Expected {}, found '{}'.",
                                            base.item_noun(),
                                            shorten(text)
                                        ),
                                    )
                                    .with_label(format!("'{field_name}' is {ty}"))
                                    .with_code("type"),
                                );
                                return None;
                            }
                        }
                    }
                    Cow::Owned(numbers)
                }
            };
            return self
                .numeric(&numbers, value.span, problems)
                .map(Literal::Value);
        }
        let atoms: &[Atom] = match &value.items {
            Items::Atoms(atoms) => atoms,
            Items::Numbers(list) if list.values.is_empty() => &[],
            Items::Numbers(_) => {
                problems.push(
                    Diagnostic::error(
                        value.span,
                        format!("Expected {}, found a number.", base.item_noun()),
                    )
                    .with_label(format!("'{field_name}' is {ty}"))
                    .with_code("type"),
                );
                return None;
            }
        };
        if !ty.multi && atoms.len() != 1 {
            problems.push(
                Diagnostic::error(
                    value.span,
                    format!("expected 1 value for {ty}, found {}", atoms.len()),
                )
                .with_code("arity"),
            );
            return None;
        }
        match base {
            BaseType::Bool => {
                let mut values = Vec::with_capacity(atoms.len());
                for atom in atoms {
                    match atom {
                        Atom::Bool(_, b) => values.push(*b),
                        other => {
                            problems.push(self.wrong(other));
                            return None;
                        }
                    }
                }
                Some(Literal::Value(if ty.multi {
                    Value::Bools(values)
                } else {
                    Value::Bool(values[0])
                }))
            }
            BaseType::String => {
                let mut values = Vec::with_capacity(atoms.len());
                for atom in atoms {
                    match atom {
                        Atom::String(s) => {
                            if let Some(diagnostic) = (self.disallowed)(s) {
                                problems.push(diagnostic);
                                return None;
                            }
                            values.push(s.value.clone());
                        }
                        other => {
                            problems.push(self.wrong(other));
                            return None;
                        }
                    }
                }
                Some(Literal::Value(if ty.multi {
                    Value::Strings(values)
                } else {
                    Value::String(values.pop().unwrap_or_default())
                }))
            }
            BaseType::Node => Some(Literal::Nodes(atoms)),
            _ => unreachable!("numeric types are handled above"),
        }
    }

    /// "Expected a string, found '3'.": an atom of the wrong kind.
    pub fn wrong(&self, atom: &Atom) -> Diagnostic {
        let (ty, field_name) = (self.ty, self.field_name);
        let text = &self.text[atom.span().range()];
        Diagnostic::error(
            atom.span(),
            format!(
                "Expected {}, found '{}'.",
                ty.base.item_noun(),
                shorten(text)
            ),
        )
        .with_label(format!("'{field_name}' is {ty}"))
        .with_code("type")
    }

    fn numeric(
        &self,
        numbers: &[f64],
        span: Span,
        problems: &mut Vec<Diagnostic>,
    ) -> Option<Value> {
        let (ty, field_name) = (self.ty, self.field_name);
        let base = ty.base;
        let integral = matches!(base, BaseType::Int32 | BaseType::Image);
        if integral {
            if let Some(bad) = numbers
                .iter()
                .find(|x| x.fract() != 0.0 || **x < i32::MIN as f64 || **x > u32::MAX as f64)
            {
                problems.push(
                    Diagnostic::error(span, format!("Expected integer value, found {bad}."))
                        .with_label(format!("'{field_name}' is {ty}"))
                        .with_code("type"),
                );
                return None;
            }
        }
        if base == BaseType::Image {
            return image(numbers, span, problems);
        }
        let arity = base.arity();
        let count_ok = if ty.multi {
            numbers.len().is_multiple_of(arity)
        } else {
            numbers.len() == arity
        };
        if !count_ok {
            let plural = if arity == 1 { "number" } else { "numbers" };
            let message = if ty.multi {
                format!(
                    "expected a multiple of {arity} numbers for {ty}, found {}",
                    numbers.len()
                )
            } else {
                format!(
                    "expected {arity} {plural} for {ty}, found {}",
                    numbers.len()
                )
            };
            problems.push(
                Diagnostic::error(span, message)
                    .with_label(format!("'{field_name}' is {ty}"))
                    .with_code("arity"),
            );
            return None;
        }
        if let Some(bad) = numbers.iter().find(|x| !x.is_finite()) {
            problems.push(
                Diagnostic::error(span, format!("{bad} is out of range for '{field_name}'"))
                    .with_code("range"),
            );
            return None;
        }
        let value = match (base, ty.multi) {
            (BaseType::Int32, false) => Value::Int(numbers[0] as i32),
            (BaseType::Int32, true) => Value::Ints(numbers.iter().map(|&x| x as i32).collect()),
            (BaseType::Float | BaseType::Time, false) => Value::Float(numbers[0]),
            (BaseType::Float | BaseType::Time, true) => Value::Floats(numbers.to_vec()),
            (BaseType::Vec2f, false) => Value::Vec2([numbers[0], numbers[1]]),
            (BaseType::Vec2f, true) => {
                Value::Vec2s(numbers.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
            }
            (BaseType::Vec3f | BaseType::Color, false) => {
                Value::Vec3([numbers[0], numbers[1], numbers[2]])
            }
            (BaseType::Vec3f | BaseType::Color, true) => Value::Vec3s(
                numbers
                    .chunks_exact(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect(),
            ),
            (BaseType::Rotation, false) => Value::Rotation(self.rotation(
                [numbers[0], numbers[1], numbers[2], numbers[3]],
                span,
                problems,
            )?),
            (BaseType::Rotation, true) => {
                let mut rotations = Vec::with_capacity(numbers.len() / 4);
                for c in numbers.chunks_exact(4) {
                    rotations.push(self.rotation([c[0], c[1], c[2], c[3]], span, problems)?);
                }
                Value::Rotations(rotations)
            }
            _ => unreachable!("non-numeric base types are handled by the caller"),
        };
        if base == BaseType::Color {
            let components: &[f64] = numbers;
            if let Some(bad) = components.iter().find(|c| !(0.0..=1.0).contains(*c)) {
                problems.push(
                    Diagnostic::error(span, format!("colour component {bad} is outside [0, 1]"))
                        .with_label(format!("'{field_name}' is {ty}"))
                        .with_code("range"),
                );
                return None;
            }
        }
        Some(value)
    }

    /// Old files leave rotation axes unnormalised: the axis is normalised; a zero axis is only
    /// accepted with a zero angle.
    fn rotation(
        &self,
        r: [f64; 4],
        span: Span,
        problems: &mut Vec<Diagnostic>,
    ) -> Option<[f64; 4]> {
        let length = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        if length == 0.0 {
            if r[3] == 0.0 {
                return Some([0.0, 0.0, 1.0, 0.0]);
            }
            let diagnostic = Diagnostic::error(
                span,
                format!(
                    "a rotation of {} about the axis 0 0 0 has no direction",
                    r[3]
                ),
            )
            .with_label("the axis is zero")
            .with_code("zero-axis");
            if self.strict {
                problems.push(
                    diagnostic.with_note(
                        "write an axis (0 1 0 for a heading), or 0 1 0 0 for no rotation",
                    ),
                );
                return None;
            }
            // Lenient: what viewers do with such files.
            let mut diagnostic = diagnostic.with_note("read as no rotation");
            diagnostic.severity = regatta_parser::Severity::Warning;
            problems.push(diagnostic);
            return Some([0.0, 0.0, 1.0, 0.0]);
        }
        Some([r[0] / length, r[1] / length, r[2] / length, r[3]])
    }
}

fn image(numbers: &[f64], span: Span, problems: &mut Vec<Diagnostic>) -> Option<Value> {
    if numbers.len() < 3 {
        problems.push(
            Diagnostic::error(span, "an SFImage starts with width, height and components")
                .with_code("arity"),
        );
        return None;
    }
    let (width, height, components) = (numbers[0], numbers[1], numbers[2]);
    if width < 0.0 || height < 0.0 || !(0.0..=4.0).contains(&components) {
        problems.push(
            Diagnostic::error(
                span,
                "SFImage width and height must be ≥ 0, components 0 to 4",
            )
            .with_code("range"),
        );
        return None;
    }
    let expected = (width * height) as usize;
    if numbers.len() - 3 != expected {
        problems.push(
            Diagnostic::error(
                span,
                format!(
                    "an SFImage of {width}×{height} needs {expected} pixel values, found {}",
                    numbers.len() - 3
                ),
            )
            .with_code("arity"),
        );
        return None;
    }
    Some(Value::Image(Image {
        width: width as u32,
        height: height as u32,
        components: components as u8,
        pixels: numbers[3..].iter().map(|&x| x as u32).collect(),
    }))
}

/// Written text as messages quote it: at most 40 characters.
pub(crate) fn shorten(text: &str) -> String {
    let mut shown: String = text.chars().take(40).collect();
    if shown.len() < text.len() {
        shown.push('…');
    }
    shown
}
