//! Tokens of the shading language, each with its line and column (1-based).

use super::ShaderError;

/// A source position.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Pos {
    /// Line, from 1.
    pub line: u32,
    /// Column (in characters), from 1.
    pub col: u32,
}

/// Token kinds.
#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    /// A number literal.
    Num(f64),
    /// An identifier or keyword.
    Ident(String),
    /// Punctuation or operator.
    Sym(&'static str),
    /// End of input.
    Eof,
}

/// A token and where it starts.
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// What it is.
    pub tok: Tok,
    /// Where it starts.
    pub pos: Pos,
}

const SYMBOLS: [&str; 27] = [
    "<=", ">=", "==", "!=", "&&", "||", "+=", "-=", "*=", "/=", "(", ")", "{", "}", ",", ";", "=", "<", ">", "+", "-",
    "*", "/", "!", "?", ":", ".",
];

/// Splits `src` into tokens; `//` and `/* */` comments are skipped.
pub fn lex(src: &str) -> Result<Vec<Token>, ShaderError> {
    let chars: Vec<char> = src.chars().collect();
    let (mut i, mut line, mut col) = (0usize, 1u32, 1u32);
    let mut out = Vec::new();
    let advance = |i: &mut usize, line: &mut u32, col: &mut u32, n: usize, chars: &[char]| {
        for _ in 0..n {
            if chars[*i] == '\n' {
                *line += 1;
                *col = 1;
            } else {
                *col += 1;
            }
            *i += 1;
        }
    };
    while i < chars.len() {
        let c = chars[i];
        let pos = Pos { line, col };
        if c.is_whitespace() {
            advance(&mut i, &mut line, &mut col, 1, &chars);
            continue;
        }
        if c == '/' && chars.get(i + 1) == Some(&'/') {
            while i < chars.len() && chars[i] != '\n' {
                advance(&mut i, &mut line, &mut col, 1, &chars);
            }
            continue;
        }
        if c == '/' && chars.get(i + 1) == Some(&'*') {
            advance(&mut i, &mut line, &mut col, 2, &chars);
            loop {
                if i + 1 >= chars.len() {
                    return Err(ShaderError::at(pos, "unterminated /* comment"));
                }
                if chars[i] == '*' && chars[i + 1] == '/' {
                    advance(&mut i, &mut line, &mut col, 2, &chars);
                    break;
                }
                advance(&mut i, &mut line, &mut col, 1, &chars);
            }
            continue;
        }
        if c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit())) {
            let start = i;
            let mut j = i;
            while j < chars.len() && (chars[j].is_ascii_digit() || chars[j] == '.') {
                j += 1;
            }
            if j < chars.len() && (chars[j] == 'e' || chars[j] == 'E') {
                let mut k = j + 1;
                if k < chars.len() && (chars[k] == '+' || chars[k] == '-') {
                    k += 1;
                }
                if k < chars.len() && chars[k].is_ascii_digit() {
                    j = k;
                    while j < chars.len() && chars[j].is_ascii_digit() {
                        j += 1;
                    }
                }
            }
            let text: String = chars[start..j].iter().collect();
            let value: f64 = text.parse().map_err(|_| ShaderError::at(pos, format!("bad number {text:?}")))?;
            if !value.is_finite() {
                return Err(ShaderError::at(pos, format!("number {text} is out of range")));
            }
            out.push(Token { tok: Tok::Num(value), pos });
            advance(&mut i, &mut line, &mut col, j - start, &chars);
            continue;
        }
        if c.is_alphabetic() || c == '_' {
            let start = i;
            let mut j = i;
            while j < chars.len() && (chars[j].is_alphanumeric() || chars[j] == '_') {
                j += 1;
            }
            out.push(Token { tok: Tok::Ident(chars[start..j].iter().collect()), pos });
            advance(&mut i, &mut line, &mut col, j - start, &chars);
            continue;
        }
        let rest2: String = chars[i..(i + 2).min(chars.len())].iter().collect();
        let sym = SYMBOLS.iter().find(|s| rest2.starts_with(**s));
        match sym {
            Some(s) => {
                out.push(Token { tok: Tok::Sym(s), pos });
                advance(&mut i, &mut line, &mut col, s.len(), &chars);
            }
            None => return Err(ShaderError::at(pos, format!("unexpected character {c:?}"))),
        }
    }
    out.push(Token { tok: Tok::Eof, pos: Pos { line, col } });
    Ok(out)
}
