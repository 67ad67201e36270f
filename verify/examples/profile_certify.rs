//! Certify a spec many times in a loop (for profilers).
fn main() {
    let path = std::env::args().nth(1).expect("spec path");
    let n: usize = std::env::args().nth(2).map_or(2000, |s| s.parse().unwrap());
    let text = std::fs::read_to_string(path).unwrap();
    let start = std::time::Instant::now();
    for _ in 0..n {
        let spec = spec::parse_spec(&text).unwrap();
        let cert = spec::certify(&spec);
        std::hint::black_box(cert.json);
    }
    eprintln!("{:.1} us per certificate", start.elapsed().as_secs_f64() * 1e6 / n as f64);
}
