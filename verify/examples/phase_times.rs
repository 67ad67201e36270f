//! Time the phases of `certify` separately (parse, analyse, certificate JSON, pretty print).
use std::time::Instant;
fn main() {
    let path = std::env::args().nth(1).expect("spec path");
    let n: usize = std::env::args().nth(2).map_or(5000, |s| s.parse().unwrap());
    let text = std::fs::read_to_string(path).unwrap();
    let t = Instant::now();
    for _ in 0..n {
        std::hint::black_box(serde_json::from_str::<serde_json::Value>(&text).unwrap());
    }
    let json_parse = t.elapsed().as_secs_f64() * 1e6 / n as f64;
    let t = Instant::now();
    for _ in 0..n {
        std::hint::black_box(spec::parse_spec(&text).unwrap());
    }
    let parse = t.elapsed().as_secs_f64() * 1e6 / n as f64;
    let spec = spec::parse_spec(&text).unwrap();
    let t = Instant::now();
    for _ in 0..n {
        std::hint::black_box(generator::analyse(&spec.system, &spec.settings.pipeline));
    }
    let analyse = t.elapsed().as_secs_f64() * 1e6 / n as f64;
    let a = generator::analyse(&spec.system, &spec.settings.pipeline);
    let t = Instant::now();
    for _ in 0..n {
        std::hint::black_box(spec::certificate_json(&spec, &a));
    }
    let cert = t.elapsed().as_secs_f64() * 1e6 / n as f64;
    let c = spec::certificate_json(&spec, &a);
    let t = Instant::now();
    for _ in 0..n {
        std::hint::black_box(spec::to_pretty_json(&c));
    }
    let pretty = t.elapsed().as_secs_f64() * 1e6 / n as f64;
    println!("json parse {json_parse:.1} us, parse_spec {parse:.1} us, analyse {analyse:.1} us, certificate_json {cert:.1} us, pretty {pretty:.1} us");
}
