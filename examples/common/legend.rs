//! Where a chart's legend goes so that it covers no curve: the first free corner of the plotting area, or,
//! when every corner holds data, the upper right corner with the y range extended so that a band above the
//! data is left free for it. Shared by the studies' plot modules (`#[path]`-included), so that all of them
//! place legends by the same rule.
//!
//! Coordinates are normalised to the plotting area: `(0, 0)` lower left, `(1, 1)` upper right.

use plotters::chart::SeriesLabelPosition;

/// Pixels per character of a legend label, relative to the font size (a conservative sans-serif average).
const CHAR_WIDTH: f64 = 0.62;
/// Pixels of a legend box beyond its text: the line sample, the gaps and the border.
const BOX_EXTRA_WIDTH: f64 = 48.0;
/// Clear space kept between the legend box and any data point, in pixels.
const CLEARANCE: f64 = 6.0;

/// A legend's size in pixels for the given labels and font size.
pub fn legend_size(labels: &[&str], font_px: f64) -> (f64, f64) {
    let chars = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0) as f64;
    let width = CHAR_WIDTH * font_px * chars + BOX_EXTRA_WIDTH;
    let height = labels.len() as f64 * (font_px + 6.0) + 12.0;
    (width, height)
}

/// Where the legend goes.
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    pub position: SeriesLabelPosition,
    /// The factor by which the y span must grow upwards to leave the legend's band free (1 when a corner is
    /// free already).
    pub headroom: f64,
}

/// The placement of a legend of `legend_px` pixels in a plotting area of `area_px` pixels over `curves`,
/// each a polyline in normalised coordinates (segments are checked, not only their points).
pub fn place(curves: &[Vec<(f64, f64)>], area_px: (f64, f64), legend_px: (f64, f64)) -> Placement {
    let (w, h) = (
        ((legend_px.0 + 2.0 * CLEARANCE) / area_px.0).min(1.0),
        ((legend_px.1 + 2.0 * CLEARANCE) / area_px.1).min(1.0),
    );
    // Corners in order of preference, as boxes (x0, y0, x1, y1) in normalised coordinates.
    let corners = [
        (
            SeriesLabelPosition::UpperRight,
            (1.0 - w, 1.0 - h, 1.0, 1.0),
        ),
        (SeriesLabelPosition::UpperLeft, (0.0, 1.0 - h, w, 1.0)),
        (SeriesLabelPosition::LowerRight, (1.0 - w, 0.0, 1.0, h)),
        (SeriesLabelPosition::LowerLeft, (0.0, 0.0, w, h)),
    ];
    for (position, rect) in corners {
        if !curves.iter().any(|c| polyline_hits(c, rect)) {
            return Placement {
                position,
                headroom: 1.0,
            };
        }
    }
    // Every corner holds data: stretch the y span so that the data fill only the lower 1 − h of the area.
    Placement {
        position: SeriesLabelPosition::UpperRight,
        headroom: 1.0 / (1.0 - h).max(0.2),
    }
}

/// Normalises a point of a linear axis range.
pub fn normalise(v: f64, range: (f64, f64)) -> f64 {
    if range.1 > range.0 {
        (v - range.0) / (range.1 - range.0)
    } else {
        0.5
    }
}

fn polyline_hits(points: &[(f64, f64)], rect: (f64, f64, f64, f64)) -> bool {
    let inside = |p: (f64, f64)| p.0 >= rect.0 && p.0 <= rect.2 && p.1 >= rect.1 && p.1 <= rect.3;
    if points.iter().any(|&p| inside(p)) {
        return true;
    }
    // A long segment can cross the box with both ends outside: sample it.
    points.windows(2).any(|s| {
        let (a, b) = (s[0], s[1]);
        let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()) / 0.01).ceil() as usize;
        (1..steps).any(|k| {
            let t = k as f64 / steps as f64;
            inside((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_free_corner_is_used_and_a_full_plot_gets_headroom() {
        // A rising line leaves the upper left and lower right corners free.
        let rising = vec![(0.0, 0.0), (1.0, 1.0)];
        let p = place(&[rising], (800.0, 300.0), (150.0, 40.0));
        assert_eq!(p.position, SeriesLabelPosition::UpperLeft);
        assert_eq!(p.headroom, 1.0);
        // Noise filling the whole area: no corner is free, the span grows by 1 / (1 − h).
        let noise: Vec<(f64, f64)> = (0..=200)
            .map(|i| (i as f64 / 200.0, if i % 2 == 0 { 0.0 } else { 1.0 }))
            .collect();
        let p = place(&[noise], (800.0, 300.0), (150.0, 48.0));
        assert_eq!(p.position, SeriesLabelPosition::UpperRight);
        assert!((p.headroom - 1.0 / (1.0 - 60.0 / 300.0)).abs() < 1e-12);
    }
}
