//! Plain tables of text cells, rendered as aligned text for a terminal or as Markdown.

/// How a column's cells line up.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Align {
    /// Flush left (names).
    Left,
    /// Flush right (numbers).
    Right,
}

/// A table: a header row, then rows of the same length.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Table {
    header: Vec<(String, Align)>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column titles and alignments.
    pub fn new<S: Into<String>>(columns: impl IntoIterator<Item = (S, Align)>) -> Self {
        Table {
            header: columns.into_iter().map(|(t, a)| (t.into(), a)).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row; missing cells are empty, extra cells are dropped.
    pub fn push<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) {
        let mut row: Vec<String> = cells.into_iter().map(Into::into).collect();
        row.resize(self.header.len(), String::new());
        self.rows.push(row);
    }

    /// Number of rows (the header excluded).
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The width of every column in characters (not bytes: `°` and `Φ` count once).
    fn widths(&self) -> Vec<usize> {
        self.header
            .iter()
            .enumerate()
            .map(|(c, (title, _))| {
                self.rows
                    .iter()
                    .map(|row| row[c].chars().count())
                    .chain([title.chars().count()])
                    .max()
                    .unwrap_or(0)
            })
            .collect()
    }

    /// Aligned columns separated by two spaces, one line per row, header first; no trailing
    /// spaces.
    pub fn to_text(&self) -> String {
        let widths = self.widths();
        let mut out = String::new();
        let titles: Vec<String> = self.header.iter().map(|(t, _)| t.clone()).collect();
        for row in std::iter::once(&titles).chain(&self.rows) {
            let mut line = String::new();
            for (c, cell) in row.iter().enumerate() {
                if c > 0 {
                    line.push_str("  ");
                }
                let pad = " ".repeat(widths[c] - cell.chars().count());
                match self.header[c].1 {
                    Align::Left => {
                        line.push_str(cell);
                        line.push_str(&pad);
                    }
                    Align::Right => {
                        line.push_str(&pad);
                        line.push_str(cell);
                    }
                }
            }
            out.push_str(line.trim_end());
            out.push('\n');
        }
        out
    }

    /// A GitHub-flavoured Markdown table (`|` in cells escaped).
    pub fn to_markdown(&self) -> String {
        let escape = |cell: &str| cell.replace('|', "\\|");
        let mut out = String::new();
        let line = |cells: &mut dyn Iterator<Item = String>| {
            let cells: Vec<String> = cells.collect();
            format!("| {} |\n", cells.join(" | "))
        };
        out.push_str(&line(&mut self.header.iter().map(|(t, _)| escape(t))));
        out.push_str(&line(&mut self.header.iter().map(|(_, a)| {
            match a {
                Align::Left => ":---",
                Align::Right => "---:",
            }
            .to_string()
        })));
        for row in &self.rows {
            out.push_str(&line(&mut row.iter().map(|c| escape(c))));
        }
        out
    }
}

impl std::fmt::Display for Table {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.to_text())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Table {
        let mut t = Table::new([("name", Align::Left), ("angle", Align::Right)]);
        t.push(["a", "1.5°"]);
        t.push(["longer|name", "12.25°"]);
        t
    }

    #[test]
    fn text_columns_line_up_by_characters() {
        let text = sample().to_text();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "name          angle");
        assert_eq!(lines[1], "a              1.5°");
        assert_eq!(lines[2], "longer|name  12.25°");
        let ends: Vec<usize> = lines.iter().map(|l| l.chars().count()).collect();
        assert!(ends.iter().all(|&e| e == ends[0]), "{text}");
    }

    #[test]
    fn markdown_has_a_separator_row_and_escapes_pipes() {
        let md = sample().to_markdown();
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(lines[0], "| name | angle |");
        assert_eq!(lines[1], "| :--- | ---: |");
        assert_eq!(lines[3], "| longer\\|name | 12.25° |");
    }

    #[test]
    fn short_rows_are_padded() {
        let mut t = Table::new([("a", Align::Left), ("b", Align::Right)]);
        t.push(["x"]);
        assert_eq!(t.len(), 1);
        assert_eq!(t.to_text(), "a  b\nx\n");
    }
}
