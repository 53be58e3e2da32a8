//! Log-axis ranges and the text of tick marks and point labels.

use super::MAX_LABEL_CHARS;

/// Log-axis range covering `values` with some margin, widened to whole decades so that the axis
/// always has tick marks (and nudged outwards so the end decades survive rounding in plotters'
/// tick placement).
pub(super) fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !(lo.is_finite() && hi.is_finite()) {
        return (1.0 - 1e-9, 10.0 + 1e-8);
    }
    let lo = 10f64.powf((lo / 1.25).log10().floor()) * (1.0 - 1e-9);
    let hi = 10f64.powf((hi * 1.25).log10().ceil()) * (1.0 + 1e-9);
    if lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo {
        (lo, hi)
    } else {
        (1.0 - 1e-9, 10.0 + 1e-8)
    }
}

/// Tick label for a log axis: plain decimals for moderate magnitudes, `1e-5` style otherwise.
pub(super) fn format_tick(v: f64) -> String {
    if !v.is_finite() || v == 0.0 {
        return format!("{v}");
    }
    let exp = v.abs().log10().floor() as i32;
    if (-3..=4).contains(&exp) {
        let decimals = (2 - exp).max(0) as usize;
        trim_zeros(format!("{v:.decimals$}"))
    } else {
        let mantissa = v / 10f64.powi(exp);
        let (mantissa, exp) = if mantissa.abs() >= 9.995 { (mantissa / 10.0, exp + 1) } else { (mantissa, exp) };
        format!("{}e{exp}", trim_zeros(format!("{mantissa:.2}")))
    }
}

fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

pub(super) fn truncate_label(label: &str) -> String {
    if label.chars().count() <= MAX_LABEL_CHARS {
        label.to_string()
    } else {
        let mut s: String = label.chars().take(MAX_LABEL_CHARS - 1).collect();
        s.push('…');
        s
    }
}
