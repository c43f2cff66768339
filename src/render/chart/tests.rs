//! The charts' pictures: series, bars, marks and cells where their values put them.

use super::heat::{heat_colour, heat_level, square};
use super::*;

const RED: [u8; 3] = [200, 20, 20];
const BLUE: [u8; 3] = [20, 60, 200];

fn rgb(p: &Pixmap, x: f32, y: f32) -> [u8; 3] {
    let c = p.pixel(x.round() as u32, y.round() as u32).unwrap();
    [c.red(), c.green(), c.blue()]
}

fn chart(series: Vec<Series>, marks: Vec<Mark>) -> Chart {
    let scale = |label: &str, hi| Scale {
        label: label.into(),
        lo: 0.0,
        hi,
        whole: false,
    };
    Chart {
        title: "A chart".into(),
        x: scale("slice", 10.0),
        y: scale("ΔI (bits)", 1.0),
        series,
        marks,
    }
}

#[test]
fn a_line_passes_through_its_points() {
    let c = chart(
        vec![Series {
            name: String::new(),
            style: Style::Line,
            colour: RED,
            points: vec![[0.0, 0.5], [10.0, 0.5]],
        }],
        vec![],
    );
    let p = draw_charts(std::slice::from_ref(&c), 600, 400).unwrap();
    let plot = plot_of(&c, (0.0, 0.0, 600.0, 400.0), font_scale(400));
    assert_eq!(rgb(&p, plot.px(3.3), plot.py(0.5)), RED);
    assert_eq!(rgb(&p, plot.px(3.3), plot.py(0.75)), [255, 255, 255]);
    // The axes are inked, the page's corner is white.
    assert_eq!(rgb(&p, plot.left, plot.py(0.3)), INK);
    assert_eq!(rgb(&p, 0.0, 0.0), [255, 255, 255]);
    assert!(plot.left > 0.0 && plot.right < 600.0 && plot.top > 0.0 && plot.bottom < 400.0);
}

#[test]
fn bars_of_two_series_stand_side_by_side_and_marks_cross_the_plot() {
    let bars = |colour, y| Series {
        name: format!("{colour:?}"),
        style: Style::Bars,
        colour,
        points: vec![[2.0, y], [4.0, y]],
    };
    let mark = Mark {
        x: 7.0,
        colour: BLUE,
        name: "boundary".into(),
    };
    let c = chart(vec![bars(RED, 0.4), bars(BLUE, 0.8)], vec![mark]);
    let p = draw_charts(std::slice::from_ref(&c), 800, 500).unwrap();
    let plot = plot_of(&c, (0.0, 0.0, 800.0, 500.0), font_scale(500));
    // Bars 0.8 of the slot (2) wide, shared by two: the red one left of x, the blue right.
    let (left, right) = (plot.px(4.0 - 0.4), plot.px(4.0 + 0.4));
    assert_eq!(rgb(&p, left, plot.py(0.2)), RED);
    // (Low in the bar: the legend, large at this size, covers the least at the top left.)
    assert_eq!(rgb(&p, right, plot.py(0.3)), BLUE);
    // Above the red bar's top, below the blue's: the grid's white.
    assert_ne!(rgb(&p, left, plot.py(0.6)), RED);
    let x = plot.px(7.0);
    let crossed = (0..40).any(|i| rgb(&p, x, plot.py(0.3) + i as f32) == BLUE);
    assert!(crossed);
}

#[test]
fn heat_cells_are_coloured_by_their_counts_on_a_log_scale() {
    assert!(heat_level(1, 1000).abs() < 1e-12);
    assert!((heat_level(1000, 1000) - 1.0).abs() < 1e-12);
    assert!((heat_level(10, 1000) - 1.0 / 3.0).abs() < 1e-12);
    assert_eq!(heat_colour(0.0), [255, 237, 160]);
    assert_eq!(heat_colour(1.0), [128, 0, 38]);
    let map = HeatMap {
        title: "joint histogram".into(),
        x_label: "bin of slab 1".into(),
        y_label: "bin of slab 2".into(),
        bins: 4,
        cells: vec![[0, 0, 1000], [1, 3, 10], [3, 3, 1]],
    };
    let p = draw_heat_map(&map, 700, 500).unwrap();
    let (left, bottom, cell) = square(&map, 700, 500).unwrap();
    let at = |x: f32, y: f32| rgb(&p, left + (x + 0.5) * cell, bottom - (y + 0.5) * cell);
    assert_eq!(at(0.0, 0.0), heat_colour(1.0));
    assert_eq!(at(1.0, 3.0), heat_colour(1.0 / 3.0));
    assert_eq!(at(3.0, 3.0), heat_colour(0.0));
    // An empty cell off the diagonal stays white.
    assert_eq!(at(2.0, 0.0), [255, 255, 255]);
    assert!(draw_heat_map(&map, 0, 10).is_err());
}

#[test]
fn the_legend_stands_where_it_covers_least() {
    let flat = |y: f64| Series {
        name: "the curve".into(),
        style: Style::Line,
        colour: RED,
        points: vec![[0.0, y], [10.0, y]],
    };
    let mark = |x| Mark {
        x,
        colour: BLUE,
        name: "boundary".into(),
    };
    // A curve low in the plot: the legend top right, over none of it.
    let low = chart(vec![flat(0.05)], vec![]);
    let p = draw_charts(std::slice::from_ref(&low), 800, 500).unwrap();
    let plot = plot_of(&low, (0.0, 0.0, 800.0, 500.0), font_scale(500));
    assert_eq!(rgb(&p, plot.px(9.8), plot.py(0.05)), RED);
    // The legend's swatch is the one red pixel far above the curve.
    let swatch = (plot.top as u32..plot.py(0.5) as u32)
        .flat_map(|y| (plot.px(5.0) as u32..plot.right as u32).map(move |x| (x, y)))
        .any(|(x, y)| rgb(&p, x as f32, y as f32) == RED);
    assert!(swatch, "no legend top right");
    // A curve along the top with a mark at the right: the legend bottom left, the curve whole.
    let high = chart(vec![flat(0.97)], vec![mark(9.5)]);
    let p = draw_charts(std::slice::from_ref(&high), 800, 500).unwrap();
    let plot = plot_of(&high, (0.0, 0.0, 800.0, 500.0), font_scale(500));
    for x in [0.2, 1.0, 5.0, 9.0, 9.8] {
        assert_eq!(rgb(&p, plot.px(x), plot.py(0.97)), RED, "at {x}");
    }
    let crossed = (0..20).any(|i| rgb(&p, plot.px(9.5), plot.py(0.1) - i as f32) == BLUE);
    assert!(crossed, "the mark is covered");
    // The red swatch below the middle and left of it.
    let below = (plot.py(0.5) as u32..plot.bottom as u32)
        .flat_map(|y| (plot.left as u32..plot.px(5.0) as u32).map(move |x| (x, y)))
        .any(|(x, y)| rgb(&p, x as f32, y as f32) == RED);
    assert!(below, "no legend bottom left");
}
