//! The cells of a record's CSV as spreadsheets and data tools write it: cells in quotes (`"t [s]"`, with `""` for
//! a quote inside), in locales with a decimal comma `;` between cells and `1,5` for 1.5, and tab-separated text
//! (a spreadsheet's "Text (Tab delimited)", MATLAB's `writematrix` with a tab delimiter).

use std::borrow::Cow;

/// How a record's CSV is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dialect {
    /// Between cells: `,`, or `;` where the decimal separator is a comma, or a tab.
    pub delimiter: char,
    /// Whether a comma in a number is its decimal separator (`0,25`).
    pub decimal_comma: bool,
}

impl Dialect {
    /// The dialect of a file whose header is `header`: `;` between cells when the header has a `;` and no `,`
    /// outside quotes (the CSV a spreadsheet writes where the decimal separator is a comma), a tab when it has tabs
    /// and neither, else `,`. With `;` or a tab a comma in a number can only be its decimal separator.
    pub fn of_header(header: &str) -> Dialect {
        let (mut commas, mut semicolons, mut tabs, mut quoted) = (0, 0, 0, false);
        for c in header.chars() {
            match c {
                '"' => quoted = !quoted,
                ',' if !quoted => commas += 1,
                ';' if !quoted => semicolons += 1,
                '\t' if !quoted => tabs += 1,
                _ => {}
            }
        }
        let delimiter = match (commas, semicolons, tabs) {
            (0, 1.., _) => ';',
            (0, 0, 1..) => '\t',
            _ => ',',
        };
        Dialect {
            delimiter,
            decimal_comma: delimiter != ',',
        }
    }

    /// The cells of `line`, trimmed; a cell in quotes without them (and `""` inside as one quote).
    pub fn cells<'a>(&self, line: &'a str) -> Vec<Cow<'a, str>> {
        let mut cells = Vec::new();
        let mut rest = line;
        // Blanks around a cell, but never the delimiter itself (a tab): `1\t\t2` has an empty cell.
        let blank = |c: char| c.is_whitespace() && c != self.delimiter;
        loop {
            let trimmed = rest.trim_start_matches(blank);
            let (cell, after) = match trimmed.strip_prefix('"') {
                Some(body) => quoted_cell(body, self.delimiter),
                None => match trimmed.find(self.delimiter) {
                    Some(i) => (
                        Cow::Borrowed(trimmed[..i].trim_matches(blank)),
                        Some(&trimmed[i + 1..]),
                    ),
                    None => (Cow::Borrowed(trimmed.trim_matches(blank)), None),
                },
            };
            cells.push(cell);
            match after {
                Some(next) => rest = next,
                None => return cells,
            }
        }
    }

    /// The text of a number cell as Rust parses it: `0,25` → `0.25` with a decimal comma.
    pub fn number_text<'a>(&self, cell: &'a str) -> Cow<'a, str> {
        if self.decimal_comma && cell.contains(',') {
            Cow::Owned(cell.replacen(',', ".", 1))
        } else {
            Cow::Borrowed(cell)
        }
    }
}

/// A quoted cell from after its opening quote: its text and what follows its delimiter (None at the end of the
/// line). A cell whose quote is not closed runs to the end of the line.
fn quoted_cell(body: &str, delimiter: char) -> (Cow<'_, str>, Option<&str>) {
    let mut text = String::new();
    let mut chars = body.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        if c != '"' {
            text.push(c);
            continue;
        }
        if chars.next_if(|&(_, n)| n == '"').is_some() {
            text.push('"');
            continue;
        }
        // The closing quote: anything up to the delimiter is ignored, as spreadsheets do.
        let after = &body[i + 1..];
        return match after.find(delimiter) {
            Some(d) => (Cow::Owned(text), Some(&after[d + 1..])),
            None => (Cow::Owned(text), None),
        };
    }
    (Cow::Owned(text), None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoted_cells_and_delimiters() {
        let comma = Dialect::of_header("t,x");
        assert_eq!(
            comma,
            Dialect {
                delimiter: ',',
                decimal_comma: false
            }
        );
        assert_eq!(
            comma.cells(" \"t [s]\" , x ,\"a \"\"b\"\", c\""),
            ["t [s]", "x", "a \"b\", c"]
        );
        assert_eq!(comma.cells("1,,2"), ["1", "", "2"]);
        assert_eq!(comma.cells("\"open"), ["open"]);
        let semicolon = Dialect::of_header("\"t [s]\";\"x, measured\"");
        assert_eq!(
            semicolon,
            Dialect {
                delimiter: ';',
                decimal_comma: true
            }
        );
        assert_eq!(semicolon.cells("0,5;1,25"), ["0,5", "1,25"]);
        assert_eq!(semicolon.number_text("1,25"), "1.25");
        assert_eq!(comma.number_text("1,25"), "1,25");
        let tab = Dialect::of_header("t [s]\tx [mm]");
        assert_eq!(
            tab,
            Dialect {
                delimiter: '\t',
                decimal_comma: true
            }
        );
        assert_eq!(tab.cells("0,5\t\t 2 \r"), ["0,5", "", "2"]);
        assert_eq!(tab.cells("\t1"), ["", "1"]);
        assert_eq!(tab.number_text("0,5"), "0.5");
        // A header with commas is comma-separated whatever else it holds.
        assert_eq!(Dialect::of_header("t,\tx").delimiter, ',');
    }
}
