//! The PNG plot of a run (plotters, bitmap backend): ms/frame bars per graph for every
//! dataset × TF × viewport, or, when sweeping, mean abs error vs ms/frame per series with the
//! Pareto front drawn as filled points.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::anyhow;
use plotters::prelude::*;

use super::report::{GraphBenchReport, Row};

const SIZE: (u32, u32) = (1280, 720);

pub(crate) fn palette(i: usize) -> RGBColor {
    const COLORS: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
    ];
    COLORS[i % COLORS.len()]
}

fn case_label(r: &Row) -> String {
    format!("{} {} {}x{}", r.dataset, r.tf, r.viewport[0], r.viewport[1])
}

/// Writes the plot for `report` to `path`.
pub fn write_plot(path: &Path, report: &GraphBenchReport) -> anyhow::Result<()> {
    let fail = |e: &dyn std::fmt::Display| anyhow!("--plot {}: cannot draw the plot: {e}", path.display());
    if report.rows.is_empty() {
        return Err(fail(&"no measured rows"));
    }
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let result = if report.sweep.is_some() { sweep_plot(&root, report) } else { bar_plot(&root, report) };
    result.map_err(|e| fail(&e))?;
    root.present().map_err(|e| fail(&e))?;
    Ok(())
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;
type DrawResult = Result<(), Box<dyn std::error::Error>>;

fn bar_plot(root: &Area<'_>, report: &GraphBenchReport) -> DrawResult {
    // One viewport for all rows: leave it out of the labels so they fit under their bars.
    let one_viewport = report.rows.iter().all(|r| r.viewport == report.rows[0].viewport);
    let label = |r: &Row| {
        if one_viewport { format!("{} {}", r.dataset, r.tf) } else { case_label(r) }
    };
    let mut graphs: Vec<&str> = Vec::new();
    let mut cases: Vec<String> = Vec::new();
    for r in &report.rows {
        if !graphs.contains(&r.graph.as_str()) {
            graphs.push(&r.graph);
        }
        let c = label(r);
        if !cases.contains(&c) {
            cases.push(c);
        }
    }
    let y_max = report.rows.iter().map(|r| r.median_ms).filter(|v| v.is_finite()).fold(0.0, f64::max) * 1.15;
    let clock = if report.timestamps { "GPU" } else { "wall" };
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("ms/frame ({clock} median of {} frames), {}", report.frames, report.adapter),
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(60)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..cases.len() as f64, 0.0..y_max.max(1e-3))?;
    let labels = cases.clone();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(cases.len().max(1) * 2 + 1)
        .x_label_style(("sans-serif", 11))
        .x_label_formatter(&|x| {
            let i = x.floor() as usize;
            if (x - i as f64 - 0.5).abs() < 0.26 { labels.get(i).cloned().unwrap_or_default() } else { String::new() }
        })
        .y_desc("ms/frame")
        .draw()?;
    let width = 0.8 / graphs.len() as f64;
    for (g, graph) in graphs.iter().enumerate() {
        let color = palette(g);
        let bars: Vec<Rectangle<(f64, f64)>> = report
            .rows
            .iter()
            .filter(|r| r.graph == *graph && r.median_ms.is_finite())
            .filter_map(|r| {
                let c = cases.iter().position(|c| *c == label(r))?;
                let x0 = c as f64 + 0.1 + g as f64 * width;
                Some(Rectangle::new([(x0, 0.0), (x0 + width * 0.9, r.median_ms)], color.filled()))
            })
            .collect();
        chart
            .draw_series(bars)?
            .label(graph.to_string())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], color.filled()));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    Ok(())
}

fn sweep_plot(root: &Area<'_>, report: &GraphBenchReport) -> DrawResult {
    let mut series: BTreeMap<String, Vec<&Row>> = BTreeMap::new();
    for r in report.rows.iter().filter(|r| r.error.is_some() && r.median_ms.is_finite()) {
        series.entry(format!("{} {}", r.graph, case_label(r))).or_default().push(r);
    }
    let point = |r: &Row| (r.median_ms, r.error.map_or(f64::NAN, |e| e.mean_abs));
    let finite: Vec<(f64, f64)> = series.values().flatten().map(|r| point(r)).filter(|p| p.1.is_finite()).collect();
    let x_max = finite.iter().map(|p| p.0).fold(0.0, f64::max) * 1.1;
    let y_max = finite.iter().map(|p| p.1).fold(0.0, f64::max) * 1.15;
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!(
                "{}: mean abs error vs ms/frame (filled: Pareto front), {}",
                report.sweep.as_deref().unwrap_or(""),
                report.adapter
            ),
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..x_max.max(1e-3), 0.0..y_max.max(1e-6))?;
    chart.configure_mesh().x_desc("ms/frame").y_desc("mean abs error vs converged reference").draw()?;
    for (i, (name, rows)) in series.iter().enumerate() {
        let color = palette(i);
        let points: Vec<(f64, f64)> = rows.iter().map(|r| point(r)).filter(|p| p.1.is_finite()).collect();
        chart
            .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], color.stroke_width(2)));
        chart.draw_series(rows.iter().filter(|r| point(r).1.is_finite()).map(|r| {
            let style = if r.pareto == Some(true) { color.filled() } else { color.stroke_width(2) };
            Circle::new(point(r), 6, style)
        }))?;
        chart.draw_series(rows.iter().filter(|r| point(r).1.is_finite()).map(|r| {
            Text::new(
                r.sweep_value.clone().unwrap_or_default(),
                (point(r).0, point(r).1),
                ("sans-serif", 14).into_font().color(&BLACK),
            )
        }))?;
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    Ok(())
}
