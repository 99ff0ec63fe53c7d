//! What a Mitsuba scene held that plie changed or ignored, as the scene's warnings (issue 18): the
//! library never prints, the caller shows [`crate::Scene::warnings`].

/// The warnings, one line each: emitters other than area lights, BSDFs rendered by their diffuse part,
/// shapes dropped, spectra averaged, and the other notes in order.
pub(super) fn collect(
    other_emitters: &[String],
    changed: &mut Vec<(String, String)>,
    dropped: &[String],
    spectral: bool,
    notes: Vec<String>,
) -> Vec<String> {
    let mut warnings = Vec::new();
    if !other_emitters.is_empty() {
        warnings.push(format!(
            "ignored {} emitter(s) plie does not render, only area lights: {}",
            other_emitters.len(),
            other_emitters.join(", ")
        ));
    }
    if !changed.is_empty() {
        changed.dedup();
        let list: Vec<String> = changed.iter().map(|(n, how)| format!("'{n}' ({how})")).collect();
        warnings
            .push(format!("materials plie cannot render yet were rendered by their diffuse part: {}", list.join(", ")));
    }
    if !dropped.is_empty() {
        let mut names = dropped.to_vec();
        names.dedup();
        warnings.push(format!(
            "dropped {} shape(s) from shading and shadows: plie does not render glass (or null BSDFs) yet: {}",
            dropped.len(),
            names.join(", ")
        ));
    }
    if spectral {
        warnings.push("spectra given as wavelength:value pairs were averaged to grey".into());
    }
    warnings.extend(notes);
    warnings
}
