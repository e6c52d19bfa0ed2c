//! From a PROTO's content scope to a JavaScript module, as Webots composes them: text outside
//! template blocks is written out as it stands, `%<= … >%` writes the value of its expression,
//! and `%< … >%` is code that runs where it stands (so it may wrap text in loops and
//! conditionals). A `#` comment of the PROTO text hides the template blocks on its line.
//!
//! The module keeps a map from its code back to the PROTO text, so that an error in a template
//! is reported where the PROTO wrote it.

/// Where a template block starts and whether it is an expression (`%<=`).
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// Byte offset of the `%<` in the content.
    pub start: usize,
    /// Byte range of the code inside the block.
    pub code: std::ops::Range<usize>,
    pub expression: bool,
}

/// The JavaScript module for one content scope and its map back to the content.
#[derive(Debug)]
pub(crate) struct Composed {
    pub js: String,
    /// (offset in `js`, offset in the content, length) of each stretch of template code.
    pub map: Vec<(usize, usize, usize)>,
}

/// The name of the array that collects the generated text; templates do not see it.
pub(crate) const OUT: &str = "__regatta_generated";

/// A template block that is never closed.
#[derive(Debug, PartialEq)]
pub(crate) struct Unclosed {
    pub start: usize,
}

/// The template blocks of `content`, in order.
pub(crate) fn blocks(content: &str) -> Result<Vec<Block>, Unclosed> {
    let bytes = content.as_bytes();
    let mut blocks = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            // A VRML comment runs to the end of its line and hides what it holds.
            b'#' => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    // A template block may stand inside a string (`url "%<= name >%.png"`).
                    if bytes[i] == b'%' && bytes.get(i + 1) == Some(&b'<') {
                        let block = block_at(content, i)?;
                        i = block.code.end + 2;
                        blocks.push(block);
                        continue;
                    }
                    if bytes[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
                i += 1;
            }
            b'%' if bytes.get(i + 1) == Some(&b'<') => {
                let block = block_at(content, i)?;
                i = block.code.end + 2;
                blocks.push(block);
            }
            _ => i += 1,
        }
    }
    Ok(blocks)
}

fn block_at(content: &str, start: usize) -> Result<Block, Unclosed> {
    let expression = content.as_bytes().get(start + 2) == Some(&b'=');
    let code_start = start + if expression { 3 } else { 2 };
    let end = content[code_start..]
        .find(">%")
        .map(|at| code_start + at)
        .ok_or(Unclosed { start })?;
    Ok(Block {
        start,
        code: code_start..end,
        expression,
    })
}

/// The module for `content`.
pub(crate) fn compose(content: &str) -> Result<Composed, Unclosed> {
    let blocks = blocks(content)?;
    let mut js = String::with_capacity(content.len() * 2);
    let mut map = Vec::with_capacity(blocks.len());
    js.push_str(&format!("const {OUT} = [];\n"));
    let mut text_start = 0;
    let write_text = |js: &mut String, text: &str| {
        if !text.is_empty() {
            js.push_str(OUT);
            js.push_str(".push(");
            js.push_str(&string_literal(text));
            js.push_str(");\n");
        }
    };
    for block in &blocks {
        write_text(&mut js, &content[text_start..block.start]);
        let code = &content[block.code.clone()];
        if block.expression {
            js.push_str(OUT);
            js.push_str(".push(String(");
            map.push((js.len(), block.code.start, code.len()));
            js.push_str(code);
            // On a line of its own: the expression may end in a `//` comment.
            js.push_str("\n));\n");
        } else {
            map.push((js.len(), block.code.start, code.len()));
            js.push_str(code);
            js.push('\n');
        }
        text_start = block.code.end + 2;
    }
    write_text(&mut js, &content[text_start..]);
    js.push_str(&format!("globalThis.{OUT} = {OUT}.join('');\n"));
    Ok(Composed { js, map })
}

impl Composed {
    /// The content offset that the module's `offset` came from: inside a stretch of template
    /// code exactly, elsewhere the end of the code before it (the composed glue around a
    /// block belongs to that block).
    pub fn content_offset(&self, offset: usize) -> Option<usize> {
        let mut best = None;
        for &(js, content, len) in &self.map {
            if js > offset {
                break;
            }
            best = Some(if offset <= js + len {
                content + (offset - js)
            } else {
                content + len
            });
        }
        best
    }

    /// The byte offset of 1-based `line` and `column` (in characters) in the module.
    pub fn offset_of(&self, line: usize, column: usize) -> Option<usize> {
        let line_start = if line <= 1 {
            0
        } else {
            self.js
                .match_indices('\n')
                .nth(line - 2)
                .map(|(at, _)| at + 1)?
        };
        let rest = &self.js[line_start..];
        let within = rest
            .char_indices()
            .nth(column.saturating_sub(1))
            .map(|(at, _)| at)
            .unwrap_or(rest.find('\n').unwrap_or(rest.len()));
        Some(line_start + within)
    }
}

/// `text` as a JavaScript string literal.
fn string_literal(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_skip_comments_and_enter_strings() {
        let content = "a %<= 1 >% # %< hidden >%\n url \"%<= name >%.png\" %< x; >%";
        let found = blocks(content).unwrap();
        assert_eq!(found.len(), 3);
        assert!(found[0].expression && found[1].expression && !found[2].expression);
        assert_eq!(&content[found[1].code.clone()], " name ");
        assert_eq!(blocks("x %< never closed"), Err(Unclosed { start: 2 }));
    }

    #[test]
    fn the_map_leads_back_to_the_content() {
        let content = "Box {\n  %< let s = 2; >%\n  size %<= s >% 1 1\n}";
        let composed = compose(content).unwrap();
        let at = composed.js.find("let s").unwrap();
        assert_eq!(composed.content_offset(at), content.find("let s"));
        let at = composed.js.find(" s \n").unwrap() + 1;
        assert_eq!(
            composed.content_offset(at),
            content.find("= s >%").map(|o| o + 2)
        );
    }
}
