//! temporary
fn main() {
    let text = std::fs::read_to_string("/tmp/lsc.json").unwrap();
    let spec = spec::parse_spec(&text).unwrap();
    let a = generator::analyse(&spec.system, &spec.settings.pipeline);
    let s = a.stable.as_ref().unwrap();
    let o = s.optimum.as_ref().unwrap();
    eprintln!(
        "t* {:?} inf {} choice t {:?}",
        o.infimum_parameters,
        o.infimum,
        s.choice.family_parameters.iter().map(|x| x.to_string()).collect::<Vec<_>>()
    );
}
