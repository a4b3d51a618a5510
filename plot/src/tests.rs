//! The figures' tests: sizes, where curves, thresholds and markers land (in the
//! SVG's coordinates and the PNG's pixels), and bad figures.

use super::*;

/// Two panels over t in [0, 10] s: a sine, and a flat line at 2 with a
/// threshold at 3 and an onset at 5 s.
fn demo() -> Figure {
    let t: Vec<f64> = (0..=1000).map(|i| i as f64 * 0.01).collect();
    let y: Vec<f64> = t.iter().map(|t| (t * 2.0).sin()).collect();
    let mut fig = Figure::new("demo", "t [s]");
    fig.panels
        .push(Panel::new("a", "y [-]").with_series(Series::line("sin", &t, &y)));
    fig.panels.push(
        Panel::new("b", "z [-]")
            .with_series(Series::line("flat", &t, &vec![2.0; t.len()]).colored([0, 200, 0]))
            .with_series(Series::line("threshold", &[0.0, 10.0], &[3.0, 3.0]).colored([200, 0, 0]))
            .with_marker(Marker::Vertical {
                x: 5.0,
                label: "onset".into(),
            }),
    );
    fig
}

/// The points of every `<polyline>` of colour `stroke` in an SVG document,
/// but the legend's samples (right of the plot areas).
fn polylines(svg: &str, stroke: &str) -> Vec<Vec<(f64, f64)>> {
    svg.lines()
        .filter(|l| l.contains("<polyline") && l.contains(&format!("stroke=\"{stroke}\"")))
        .map(|l| {
            let pts = l.split("points=\"").nth(1).unwrap().split('"').next().unwrap();
            pts.split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect::<Vec<(f64, f64)>>()
        })
        .filter(|p| {
            p.first()
                .is_some_and(|p| p.0 < (FIGURE_WIDTH_PX - LEGEND_WIDTH_PX) as f64)
        })
        .collect()
}

#[test]
fn image_has_the_documented_size() {
    let img = render(&demo()).unwrap();
    assert_eq!(img.width, FIGURE_WIDTH_PX);
    assert_eq!(img.height, TITLE_BAND_PX + 2 * PANEL_HEIGHT_PX + XLABEL_BAND_PX);
}

#[test]
fn the_svg_has_the_curve_and_threshold_where_they_belong() {
    let svg = render_svg(&demo()).unwrap();
    // panel b's y range: 2..3 padded by 5 %, i.e. 1.95..3.05; the flat line at 2
    // and the threshold at 3 are 1/22 of the plot height from its bottom and top
    let flat = polylines(&svg, "#00C800");
    let thr = polylines(&svg, "#C80000");
    assert_eq!((flat.len(), thr.len()), (1, 1), "{svg}");
    let (fy, ty) = (flat[0][0].1, thr[0][0].1);
    assert!(flat[0].iter().all(|p| p.1 == fy) && thr[0].iter().all(|p| p.1 == ty));
    let plot_h = (fy - ty) * 22.0 / 20.0;
    let bottom = fy + plot_h / 22.0;
    // the plot area of panel b ends above its x tick labels (24 px) in the panel's 280 px
    let panel_bottom = (TITLE_BAND_PX + 2 * PANEL_HEIGHT_PX) as f64;
    assert!(
        (panel_bottom - 24.0 - bottom).abs() <= 1.5,
        "plot bottom {bottom}, panel bottom {panel_bottom}"
    );
    assert!(plot_h > 200.0 && plot_h < 250.0, "plot height {plot_h}");
    // x: 0..10 s spans the plot's width; the flat line's ends are its edges and
    // the onset marker at 5 s halfway between them
    let (x0, x1) = (thr[0][0].0, thr[0][1].0);
    assert!(
        (x0 - (Y_DESC_PAD_PX + LEFT_MARGIN_PX) as f64).abs() <= 1.5,
        "{x0}"
    );
    assert!(
        (x1 - (FIGURE_WIDTH_PX - LEGEND_WIDTH_PX - 8) as f64).abs() <= 1.5,
        "{x1}"
    );
    let onset_x: Vec<f64> = svg
        .lines()
        .filter(|l| l.contains("<polyline") && l.contains("stroke=\"#464646\""))
        .flat_map(|l| polylines(l, "#464646"))
        .map(|p| p[0].0)
        .collect();
    assert!(!onset_x.is_empty(), "{svg}");
    assert!(
        onset_x.iter().all(|x| (x - (x0 + x1) / 2.0).abs() <= 1.0),
        "{onset_x:?} vs {x0}..{x1}"
    );
    // the sine: 1001 points over ~1100 columns stay a line of every point
    let sine = polylines(&svg, "#1F77B4");
    assert_eq!(sine.iter().map(Vec::len).sum::<usize>(), 1001);
    assert!(svg.contains("onset") && svg.contains("demo"), "{svg}");
}

#[test]
fn the_png_has_the_curve_where_the_svg_has_it() {
    let fig = demo();
    let img = render(&fig).unwrap();
    let svg = render_svg(&fig).unwrap();
    let flat = &polylines(&svg, "#00C800")[0];
    let row = flat[0].1.round() as usize;
    let col = Y_DESC_PAD_PX + LEFT_MARGIN_PX + 200;
    let green = |y: usize| {
        img.pixel(col, y)
            .is_some_and(|[r, g, b]| g > 150 && r < 120 && b < 120)
    };
    assert!((row - 2..=row + 2).any(green), "no green near row {row}");
    assert!(!(row + 6..=row + 30).any(green), "green away from row {row}");
}

#[test]
fn a_long_series_is_an_envelope_not_a_ribbon() {
    // 100 000 points of a square wave ±1 around a ramp: each column holds both
    // levels, so the envelope spans ±1 around the ramp and the mean line follows the ramp
    let t: Vec<f64> = (0..100_000).map(|i| i as f64 * 1e-4).collect();
    let y: Vec<f64> = (0..100_000)
        .map(|i| t[i] + if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let mut fig = Figure::new("envelope", "t [s]");
    fig.panels
        .push(Panel::new("p", "y [-]").with_series(Series::line("sq", &t, &y).colored([10, 20, 30])));
    let svg = render_svg(&fig).unwrap();
    let mean = polylines(&svg, "#0A141E");
    assert_eq!(mean.len(), 1);
    let n = mean[0].len();
    assert!(n > 900 && n < 1200, "{n} columns");
    let poly = svg.lines().find(|l| l.contains("<polygon")).unwrap_or("");
    assert!(poly.contains("0A141E"), "no envelope: {poly}");
}

#[test]
fn png_round_trips_through_the_decoder() {
    let img = render(&demo()).unwrap();
    let bytes = encode_png(&img).unwrap();
    let dec = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(
        (info.width as usize, info.height as usize),
        (img.width, img.height)
    );
    assert_eq!(&buf[..info.buffer_size()], &img.pixels[..]);
}

#[test]
fn bad_figures_are_reported() {
    assert!(matches!(
        render(&Figure::new("x", "t")),
        Err(PlotError::NothingToPlot)
    ));
    let mut fig = Figure::new("x", "t");
    fig.panels
        .push(Panel::new("p", "y").with_series(Series::line("s", &[1.0, 2.0], &[1.0])));
    let e = render(&fig).unwrap_err();
    assert!(e.to_string().contains("'s' has 2 x values but 1 y values"), "{e}");
    let mut fig = Figure::new("x", "t");
    fig.panels
        .push(Panel::new("p", "y").with_series(Series::line("s", &[1.0, 2.0], &[f64::NAN, f64::NAN])));
    assert!(render(&fig).is_ok(), "all-NaN y still draws the axes");
    assert!(render_svg(&fig).is_ok());
}
