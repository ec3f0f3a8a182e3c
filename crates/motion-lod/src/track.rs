//! Controls over time for one walk: the CSV track `synth --track` reads, each row applied at the
//! next cycle seam ([`MotionModel::synthesize_track`](crate::MotionModel::synthesize_track)).
//!
//! The format: a header row naming the columns, then one row per change.
//!
//! ```text
//! time,dx,dz,turn,height,style
//! 0,0,1.2,0,,normal
//! 4,0,0.8,0,,elderly
//! 8,0,1.0,25,,elderly=0.5;youthful=0.5
//! ```
//!
//! `time` (s, increasing, the first 0), `dx` and `dz` (m per cycle), `turn` (degrees per cycle,
//! positive to the left) are required; `height` (m) and `style` (a name, `data`, or a blend with `;` between
//! its parts, [`crate::style::parse_style_mix`]) are optional columns, and an empty cell keeps
//! the default (the middle of the data's heights, the data's mix of styles). This module only
//! parses; it synthesizes nothing.

use lod_policy::{Controls, StyleMix};

use crate::style::parse_style_mix_split;

/// Why a track could not be read.
#[derive(Debug, thiserror::Error)]
#[error("track line {line}: {message}")]
pub struct TrackError {
    /// The line (1-based; 1 is the header).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// The columns a track may have, in any order.
const COLUMNS: [&str; 6] = ["time", "dx", "dz", "turn", "height", "style"];

/// The index of `style` in [`COLUMNS`].
const STYLE_COLUMN: usize = 5;

/// Parses a track (see the module documentation) for a model with `styles`, a missing or empty
/// height reading `default_height`. Errors name the line: a missing required column, an unknown
/// one, a cell that is not a finite number, times that do not increase from 0, a style the model
/// does not have.
pub fn parse_track(
    text: &str,
    styles: &[String],
    default_height: f32,
) -> Result<Vec<(f64, Controls)>, TrackError> {
    // A UTF-8 byte-order mark (a spreadsheet's CSV export) is not part of the header.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let err = |line: usize, message: String| TrackError { line, message };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((header_line, header)) = lines.next() else {
        return Err(err(1, "empty: a header `time,dx,dz,turn` is needed".into()));
    };
    let names: Vec<String> = header
        .split(',')
        .map(|c| c.trim().to_ascii_lowercase())
        .collect();
    let mut at = [None::<usize>; 6];
    for (i, name) in names.iter().enumerate() {
        let Some(k) = COLUMNS.iter().position(|c| c == name) else {
            return Err(err(
                header_line,
                format!("unknown column {name:?} (columns: {})", COLUMNS.join(", ")),
            ));
        };
        if at[k].replace(i).is_some() {
            return Err(err(header_line, format!("column {name:?} is named twice")));
        }
    }
    if let Some(k) = (0..4).find(|&k| at[k].is_none()) {
        return Err(err(
            header_line,
            format!(
                "no column {:?}: time, dx, dz and turn are required",
                COLUMNS[k]
            ),
        ));
    }
    let mut rows: Vec<(f64, Controls)> = Vec::new();
    for (line, text) in lines {
        let cells: Vec<&str> = text.split(',').map(str::trim).collect();
        if cells.len() != names.len() {
            // More cells than columns in a track with styles: most likely a blend written with
            // commas, which split it.
            let hint = if cells.len() > names.len() && at[STYLE_COLUMN].is_some() {
                " (a style blend separates its parts with `;`: elderly=0.5;youthful=0.5)"
            } else {
                ""
            };
            return Err(err(
                line,
                format!("{} cells for {} columns{hint}", cells.len(), names.len()),
            ));
        }
        let cell = |k: usize| at[k].map(|i| cells[i]).filter(|c| !c.is_empty());
        let number = |k: usize| -> Result<Option<f64>, TrackError> {
            cell(k)
                .map(|c| {
                    // Within single precision, which the controls are: `1e300` became an
                    // infinite control, refused without its line.
                    c.parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite() && v.abs() <= f64::from(f32::MAX))
                        .ok_or_else(|| {
                            err(
                                line,
                                format!(
                                    "{} {c:?} is not a finite number (at most 3.4e38 in magnitude)",
                                    COLUMNS[k]
                                ),
                            )
                        })
                })
                .transpose()
        };
        let required = |k: usize| -> Result<f64, TrackError> {
            number(k)?.ok_or_else(|| err(line, format!("{} is empty", COLUMNS[k])))
        };
        let time = required(0)?;
        let (dx, dz, turn) = (required(1)?, required(2)?, required(3)?);
        let height = number(4)?.map_or(default_height, |h| h as f32);
        let style = match cell(STYLE_COLUMN) {
            None => StyleMix::DATA_MIX,
            Some(s) => parse_style_mix_split(styles, s, &[';', '+', ','])
                .map_err(|e| err(line, e.to_string()))?,
        };
        match rows.last() {
            None if time != 0.0 => {
                return Err(err(
                    line,
                    format!("the first time is {time} s: it must be 0"),
                ));
            }
            Some(&(prev, _)) if time <= prev => {
                return Err(err(
                    line,
                    format!("time {time} s does not come after {prev} s: times must increase"),
                ));
            }
            _ => {}
        }
        let controls =
            Controls::from_array([dx as f32, dz as f32, (turn as f32).to_radians(), height])
                .with_style(style);
        rows.push((time, controls));
    }
    if rows.is_empty() {
        return Err(err(header_line, "no rows after the header".into()));
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn styles() -> Vec<String> {
        ["elderly", "normal", "youthful"].map(String::from).to_vec()
    }

    #[test]
    fn rows_read_with_optional_columns_and_blends() {
        let text = "# a walk that slows and ages\nTime, dx, dz, turn, style\n0,0,1.2,0,normal\n4,0.1,0.8,-10,elderly\n8,0,1.0,25,elderly=0.5;youthful=0.5\n9,0,1.0,0,\n";
        let rows = parse_track(text, &styles(), 1.7).unwrap();
        assert_eq!(rows.len(), 4);
        // A spreadsheet's byte-order mark before the header (it gave `unknown column
        // "\u{feff}time"`).
        let marked = parse_track(&format!("\u{feff}{}", &text[29..]), &styles(), 1.7).unwrap();
        assert_eq!(marked, rows);
        assert_eq!(rows[0].0, 0.0);
        assert_eq!(rows[0].1.style, StyleMix::one(1));
        assert_eq!(rows[1].1.dx, 0.1);
        assert!((rows[1].1.turn - (-10f32).to_radians()).abs() < 1e-7);
        assert_eq!(rows[1].1.height, 1.7);
        assert_eq!(rows[2].1.style.weights[..3], [0.5, 0.0, 0.5]);
        assert_eq!(rows[3].1.style, StyleMix::DATA_MIX);
    }

    #[test]
    fn bad_tracks_name_the_line() {
        for (text, line, says) in [
            ("", 1, "header"),
            ("time,dx,dz\n0,0,1\n", 1, "turn"),
            ("time,dx,dz,turn,speed\n", 1, "unknown column"),
            ("time,dx,dz,turn\n1,0,1,0\n", 2, "must be 0"),
            ("time,dx,dz,turn\n0,0,1,0\n0,0,1,0\n", 3, "must increase"),
            ("time,dx,dz,turn\n0,0,x,0\n", 2, "not a finite number"),
            ("time,dx,dz,turn\n0,0,NaN,0\n", 2, "not a finite number"),
            (
                "time,dx,dz,turn\n0,0,1.2,0\n1,1e300,1.2,0\n",
                3,
                "at most 3.4e38",
            ),
            ("time,dx,dz,turn\n0,0,1\n", 2, "3 cells for 4 columns"),
            ("time,dx,dz,turn,style\n0,0,1,0,old\n", 2, "no style"),
            (
                "time,dx,dz,turn,style\n0,0,1,0,elderly=0.5,normal=0.5\n",
                2,
                "6 cells for 5 columns (a style blend separates its parts with `;`",
            ),
            ("time,dx,dz,turn\n", 1, "no rows"),
        ] {
            let e = parse_track(text, &styles(), 1.7).unwrap_err();
            assert_eq!(e.line, line, "{text:?}: {e}");
            assert!(e.to_string().contains(says), "{text:?}: {e}");
        }
    }
}
