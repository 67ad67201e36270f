//! Loop over certificate_json only (for profilers).
fn main() {
    let text = std::fs::read_to_string(std::env::args().nth(1).unwrap()).unwrap();
    let spec = spec::parse_spec(&text).unwrap();
    let which = std::env::args().nth(2).unwrap_or_default();
    let a = generator::analyse(&spec.system, &spec.settings.pipeline);
    for _ in 0..50000 {
        if which == "analyse" {
            std::hint::black_box(generator::analyse(&spec.system, &spec.settings.pipeline));
        } else if which == "parse" {
            std::hint::black_box(spec::parse_spec(&text).unwrap());
        } else {
            std::hint::black_box(spec::certificate_json(&spec, &a));
        }
    }
}
