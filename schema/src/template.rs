//! Expression templates in PROTO bodies: `%<= fields.height.value / 2 >%`.
//!
//! regatta evaluates the arithmetic subset of Webots' template expressions, enough for a PROTO
//! to place parts from its fields: numbers, `fields.NAME.value` (and `.defaultValue`, treated
//! the same), vector components `.x .y .z .w` (also `.r .g .b`), `Math.PI`, unary minus,
//! `+ - * /` and parentheses. Statement blocks (`%< … >%`) and anything else are not run:
//! the caller reports them.

use crate::binding::Bindings;
use crate::value::Value;

/// The result of an expression: a number or a vector (spread into its components).
#[derive(Clone, Debug, PartialEq)]
pub enum Evaluated {
    Number(f64),
    Vector(Vec<f64>),
}

/// Evaluates the inside of an expression template (`%<= … >%` or `%{= … }%`).
pub fn evaluate(template_text: &str, fields: &Bindings) -> Result<Evaluated, String> {
    let inner = template_text
        .strip_prefix("%<=")
        .and_then(|t| t.strip_suffix(">%"))
        .or_else(|| {
            template_text
                .strip_prefix("%{=")
                .and_then(|t| t.strip_suffix("}%"))
        })
        .ok_or_else(|| "only expression templates (%<= … >%) are evaluated".to_owned())?;
    let mut parser = ExprParser {
        bytes: inner.as_bytes(),
        text: inner,
        pos: 0,
        fields,
    };
    let value = parser.expr(0)?;
    parser.skip_spaces();
    if parser.pos != parser.bytes.len() {
        return Err(format!(
            "unexpected '{}' in template expression",
            &inner[parser.pos..]
        ));
    }
    Ok(value)
}

struct ExprParser<'a> {
    bytes: &'a [u8],
    text: &'a str,
    pos: usize,
    fields: &'a Bindings,
}

const MAX_NESTING: usize = 64;

impl ExprParser<'_> {
    fn skip_spaces(&mut self) {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    fn eat(&mut self, byte: u8) -> bool {
        self.skip_spaces();
        if self.bytes.get(self.pos) == Some(&byte) {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    fn expr(&mut self, depth: usize) -> Result<Evaluated, String> {
        let mut left = self.term(depth)?;
        loop {
            if self.eat(b'+') {
                let right = self.term(depth)?;
                left = combine(left, right, |a, b| a + b)?;
            } else if self.eat(b'-') {
                let right = self.term(depth)?;
                left = combine(left, right, |a, b| a - b)?;
            } else {
                return Ok(left);
            }
        }
    }

    fn term(&mut self, depth: usize) -> Result<Evaluated, String> {
        let mut left = self.unary(depth)?;
        loop {
            if self.eat(b'*') {
                let right = self.unary(depth)?;
                left = combine(left, right, |a, b| a * b)?;
            } else if self.eat(b'/') {
                let right = self.unary(depth)?;
                left = combine(left, right, |a, b| a / b)?;
            } else {
                return Ok(left);
            }
        }
    }

    fn unary(&mut self, depth: usize) -> Result<Evaluated, String> {
        if depth > MAX_NESTING {
            return Err("template expression nested too deeply".to_owned());
        }
        if self.eat(b'-') {
            let value = self.unary(depth + 1)?;
            return combine(Evaluated::Number(-1.0), value, |a, b| a * b);
        }
        if self.eat(b'+') {
            return self.unary(depth + 1);
        }
        if self.eat(b'(') {
            let value = self.expr(depth + 1)?;
            if !self.eat(b')') {
                return Err("missing ')' in template expression".to_owned());
            }
            return Ok(value);
        }
        self.skip_spaces();
        let start = self.pos;
        while self.pos < self.bytes.len()
            && (self.bytes[self.pos].is_ascii_alphanumeric()
                || matches!(self.bytes[self.pos], b'.' | b'_'))
        {
            self.pos += 1;
        }
        let word = &self.text[start..self.pos];
        if word.is_empty() {
            return Err("expected a number or fields.NAME.value in template expression".to_owned());
        }
        if word.starts_with(|c: char| c.is_ascii_digit() || c == '.') {
            // Exponents: `1e-3` stops at the '-', so take it with its sign.
            let mut end = self.pos;
            if word.ends_with(['e', 'E']) && matches!(self.bytes.get(end), Some(b'-' | b'+')) {
                end += 1;
                while end < self.bytes.len() && self.bytes[end].is_ascii_digit() {
                    end += 1;
                }
                self.pos = end;
            }
            return self.text[start..end]
                .parse::<f64>()
                .map(Evaluated::Number)
                .map_err(|_| format!("'{}' is not a number", &self.text[start..end]));
        }
        if word == "Math.PI" {
            return Ok(Evaluated::Number(std::f64::consts::PI));
        }
        let parts: Vec<&str> = word.split('.').collect();
        match parts.as_slice() {
            ["fields", name, "value" | "defaultValue", rest @ ..] => {
                let value = &self.fields.get(*name).ok_or_else(|| format!("this PROTO has no field '{name}'"))?.value;
                let value = value.as_ref().ok_or_else(|| format!("field '{name}' has no value"))?;
                let base = match value {
                    Value::Float(x) => Evaluated::Number(*x),
                    Value::Int(i) => Evaluated::Number(*i as f64),
                    Value::Bool(b) => Evaluated::Number(if *b { 1.0 } else { 0.0 }),
                    Value::Vec2(v) => Evaluated::Vector(v.to_vec()),
                    Value::Vec3(v) => Evaluated::Vector(v.to_vec()),
                    Value::Rotation(v) => Evaluated::Vector(v.to_vec()),
                    _ => return Err(format!("field '{name}' is not numeric")),
                };
                match rest {
                    [] => Ok(base),
                    [component] => {
                        let index = match *component {
                            "x" | "r" => 0,
                            "y" | "g" => 1,
                            "z" | "b" => 2,
                            "w" | "a" => 3,
                            other => return Err(format!("unknown component '.{other}'")),
                        };
                        match base {
                            Evaluated::Vector(v) if index < v.len() => Ok(Evaluated::Number(v[index])),
                            _ => Err(format!("field '{name}' has no component '.{component}'")),
                        }
                    }
                    _ => Err(format!("cannot read '{word}'")),
                }
            }
            _ => Err(format!("'{word}' is not supported in template expressions (only fields.NAME.value arithmetic is)")),
        }
    }
}

fn combine(a: Evaluated, b: Evaluated, op: impl Fn(f64, f64) -> f64) -> Result<Evaluated, String> {
    Ok(match (a, b) {
        (Evaluated::Number(x), Evaluated::Number(y)) => Evaluated::Number(op(x, y)),
        (Evaluated::Vector(v), Evaluated::Number(y)) => {
            Evaluated::Vector(v.into_iter().map(|x| op(x, y)).collect())
        }
        (Evaluated::Number(x), Evaluated::Vector(v)) => {
            Evaluated::Vector(v.into_iter().map(|y| op(x, y)).collect())
        }
        (Evaluated::Vector(u), Evaluated::Vector(v)) if u.len() == v.len() => {
            Evaluated::Vector(u.into_iter().zip(v).map(|(x, y)| op(x, y)).collect())
        }
        _ => return Err("vectors of different sizes in template expression".to_owned()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::value::{BaseType, FieldType};
    use std::collections::BTreeMap;

    #[test]
    fn arithmetic_over_fields() {
        let mut fields = BTreeMap::new();
        let float = FieldType {
            multi: false,
            base: BaseType::Float,
        };
        let vec2 = FieldType {
            multi: false,
            base: BaseType::Vec2f,
        };
        fields.insert(
            "height".to_owned(),
            crate::binding::Binding::new(float, Some(Value::Float(0.04))),
        );
        fields.insert(
            "size".to_owned(),
            crate::binding::Binding::new(vec2, Some(Value::Vec2([1.0, 2.0]))),
        );
        let eval = |t: &str| evaluate(t, &fields).unwrap();
        assert_eq!(
            eval("%<= fields.height.value / 2 >%"),
            Evaluated::Number(0.02)
        );
        assert_eq!(
            eval("%<= -(fields.size.value.y / 2 + 1e-1) >%"),
            Evaluated::Number(-1.1)
        );
        assert_eq!(
            eval("%<= fields.size.value * 2 >%"),
            Evaluated::Vector(vec![2.0, 4.0])
        );
        assert!(evaluate("%<= fields.nope.value >%", &fields).is_err());
        assert!(evaluate("%< for (;;) {} >%", &fields).is_err());
        assert!(evaluate("%<= ((((1 >%", &fields).is_err());
    }
}
