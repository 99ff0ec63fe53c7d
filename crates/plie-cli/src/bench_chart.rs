//! The chart of `plie bench`: shading time per scene, one bar per visibility mode, at the break-even
//! setting (254x254 eye rays, 4 shadow rays per light), drawn with plotters' SVG backend.

use anyhow::{anyhow, Result};
use plotters::prelude::*;

use crate::bench_data::{seconds, Plan, Results};

/// The grouped bar chart as SVG text.
pub fn svg(plan: &Plan, r: &Results) -> Result<String> {
    let (size, rays) = r.break_even_setting;
    let names: Vec<&str> = r.scenes.iter().map(|s| s.name.as_str()).collect();
    let time = |j: usize, m| seconds(&r.scenes[j], m, size, rays, r.threads);
    let max = (0..names.len()).flat_map(|j| plan.modes.iter().filter_map(move |&m| time(j, m))).fold(0.0, f64::max);
    let e = |e: &dyn std::fmt::Display| anyhow!("cannot draw the chart: {e}");
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (120 * names.len() as u32 + 240, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let caption =
            format!("Shading time, {size}x{size} eye rays, {rays} shadow rays per light, {} threads", r.threads);
        let mut chart = ChartBuilder::on(&root)
            .caption(caption, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..names.len() as f64 - 0.5, 0.0..(max * 1.1).max(1e-6))
            .map_err(|x| e(&x))?;
        let label = |x: &f64| {
            let j = x.round();
            let on = (x - j).abs() < 1e-6 && j >= 0.0;
            on.then(|| names.get(j as usize).map(|s| s.to_string())).flatten().unwrap_or_default()
        };
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(names.len() + 1)
            .x_label_formatter(&label)
            .y_desc("seconds")
            .draw()
            .map_err(|x| e(&x))?;
        let w = 0.8 / plan.modes.len() as f64;
        for (i, &m) in plan.modes.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let bars = (0..names.len()).filter_map(|j| {
                let x0 = j as f64 - 0.4 + i as f64 * w;
                Some(Rectangle::new([(x0, 0.0), (x0 + w, time(j, m)?)], color.filled()))
            });
            chart
                .draw_series(bars)
                .map_err(|x| e(&x))?
                .label(m.name())
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], color.filled()));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
    }
    Ok(buf)
}
