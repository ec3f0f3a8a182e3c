//! Markdown tables and the number formats used in `docs/tables.md`.

/// A GitHub-flavoured markdown table: a header row and rows of the same width.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    header: Vec<String>,
    /// Right-align column `i` (numbers) when `right[i]`.
    right: Vec<bool>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column titles; a title starting with `>` is right-aligned (the `>` is
    /// dropped).
    pub fn new(header: &[&str]) -> Table {
        Table {
            header: header
                .iter()
                .map(|h| h.strip_prefix('>').unwrap_or(h).to_string())
                .collect(),
            right: header.iter().map(|h| h.starts_with('>')).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row; missing cells are left empty and extra cells are dropped, so the table stays
    /// rectangular. A `|` inside a cell is escaped.
    pub fn row<S: AsRef<str>>(&mut self, cells: &[S]) {
        let mut row: Vec<String> = cells
            .iter()
            .take(self.header.len())
            .map(|c| c.as_ref().replace('|', "\\|"))
            .collect();
        row.resize(self.header.len(), String::new());
        self.rows.push(row);
    }

    /// Number of body rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when the table has no body rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The markdown text, one line per row, ending with a newline.
    pub fn render(&self) -> String {
        let line = |cells: &[String]| format!("| {} |\n", cells.join(" | "));
        let mut out = line(&self.header);
        let rule: Vec<String> = self
            .right
            .iter()
            .map(|&r| {
                if r {
                    "---:".to_string()
                } else {
                    "---".to_string()
                }
            })
            .collect();
        out.push_str(&line(&rule));
        for r in &self.rows {
            out.push_str(&line(r));
        }
        out
    }
}

/// Bytes as decimal megabytes with three significant decimals, e.g. `1.452 MB`; below 10 kB as kB.
pub fn mb(bytes: usize) -> String {
    if bytes < 10_000 {
        format!("{:.2} kB", bytes as f64 / 1e3)
    } else {
        format!("{:.3} MB", bytes as f64 / 1e6)
    }
}

/// Bytes as mebibytes (`2^20`), the unit of the paper's "MB" (94 x 100 x 186 x 8 bytes = 13.34).
pub fn mib(bytes: usize) -> String {
    format!("{:.2} MiB", bytes as f64 / (1u64 << 20) as f64)
}

/// A duration in nanoseconds with a unit that keeps three significant digits (`ns`, `µs`, `ms`, `s`).
pub fn duration_ns(ns: f64) -> String {
    if !ns.is_finite() {
        return "-".into();
    }
    let (v, unit) = if ns < 1e3 {
        (ns, "ns")
    } else if ns < 1e6 {
        (ns / 1e3, "µs")
    } else if ns < 1e9 {
        (ns / 1e6, "ms")
    } else {
        (ns / 1e9, "s")
    };
    format!("{} {unit}", sig3(v))
}

/// `v` with three significant digits for values in `[1, 1000)` (`1.23`, `12.3`, `123`), without
/// decimals from 1000 on, and with two decimals below 1.
pub fn sig3(v: f64) -> String {
    let a = v.abs();
    if a >= 100.0 {
        format!("{v:.0}")
    } else if (10.0..100.0).contains(&a) {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// A ratio as a percentage with one decimal, e.g. `10.9 %`.
pub fn percent(ratio: f64) -> String {
    format!("{:.1} %", 100.0 * ratio)
}

/// A rank triple as `40 x 40 x 60`.
pub fn ranks(r: [usize; 3]) -> String {
    format!("{} x {} x {}", r[0], r[1], r[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_renders_alignment_escapes_and_pads() {
        let mut t = Table::new(&["method", ">bytes"]);
        t.row(&["a|b", "12"]);
        t.row(&["short"]);
        t.row(&["x", "1", "dropped"]);
        assert_eq!(t.len(), 3);
        assert_eq!(
            t.render(),
            "| method | bytes |\n| --- | ---: |\n| a\\|b | 12 |\n| short |  |\n| x | 1 |\n"
        );
    }

    #[test]
    fn number_formats() {
        assert_eq!(mb(1_452_000), "1.452 MB");
        assert_eq!(mb(2_500), "2.50 kB");
        // The paper's raw samples: 94 x 100 x 186 doubles.
        assert_eq!(mib(94 * 100 * 186 * 8), "13.34 MiB");
        assert_eq!(duration_ns(532.4), "532 ns");
        assert_eq!(duration_ns(12_345.0), "12.3 µs");
        assert_eq!(duration_ns(1.5e6), "1.50 ms");
        assert_eq!(duration_ns(f64::NAN), "-");
        assert_eq!(percent(0.1087), "10.9 %");
        assert_eq!(sig3(6208.18), "6208");
        assert_eq!(sig3(12.345), "12.3");
        assert_eq!(sig3(0.714), "0.71");
        assert_eq!(ranks([40, 40, 60]), "40 x 40 x 60");
    }
}
