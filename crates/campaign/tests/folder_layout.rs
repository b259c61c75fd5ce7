//! A campaign folder is Parquet only, so polars, pandas and pyarrow read
//! it as it is: the configuration is kept in `_campaign.parquet` (the
//! shards' columns, no rows, the text in its footer). A folder an older
//! rtpipe wrote, with `_campaign.toml`, is still read, and a run of the
//! same campaign replaces that file; another campaign's is refused and
//! left as it is.

use rtpipe_campaign::{config, run, shard_path, survey, Part, Summary, KEPT, LEGACY_KEPT};
use rtpipe_testkit::Scratch;
use std::path::Path;

const CONFIG: &str = r#"
# kept as written, comments included
[campaign]
name = "layout"
systems = 9
seed = 3
shard_size = 4

[generate]
kind = "waters"
tasks = [5, 10]
utilization = [0.4, 0.8]
chains = 2
"#;

/// A campaign folder not yet made, in a scratch directory removed after
/// the test.
fn dir(name: &str) -> Scratch {
    Scratch::new(&format!("layout-{name}")).within("out")
}

fn go_with(text: &str, d: &Path) -> Result<Summary, rtpipe_campaign::Error> {
    let cfg = config::parse("t.toml", text).expect("a valid config");
    run(&cfg, text, d, Part::ALL, 2, &|| {}, &|| false)
}

fn go(d: &Path) -> Summary {
    go_with(CONFIG, d).unwrap_or_else(|e| panic!("{}: {}", e.message, e.help))
}

fn names(d: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(d)
        .expect("the folder")
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    names
}

/// A footer's key-value pairs.
type KeyValues = Vec<(String, Option<String>)>;

/// A Parquet file's row count, column paths and footer key-value pairs.
fn parquet(path: &Path) -> (u64, Vec<String>, KeyValues) {
    let footer = rtpipe_parquet::read_footer(path).expect("a Parquet file");
    (footer.rows, footer.columns, footer.key_values)
}

#[test]
fn the_folder_is_parquet_only_and_its_configuration_adds_no_row() {
    let d = dir("parquet-only");
    assert_eq!(go(&d).written, 3);
    assert_eq!(
        names(&d),
        [
            KEPT,
            "shard-000000.parquet",
            "shard-000001.parquet",
            "shard-000002.parquet"
        ]
    );
    let (rows, columns, kv) = parquet(&d.join(KEPT));
    let (shard_rows, shard_columns, _) = parquet(&shard_path(&d, 0));
    assert_eq!(rows, 0, "read as part of the folder, it adds nothing");
    assert!(shard_rows > 0);
    assert_eq!(columns, shard_columns, "the shards' columns: one schema");
    let config = kv.iter().find(|(k, _)| k == "rtpipe.config");
    assert_eq!(config.and_then(|(_, v)| v.as_deref()), Some(CONFIG));
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn an_older_folders_campaign_toml_is_read_then_replaced() {
    let d = dir("legacy");
    go(&d);
    let shards: Vec<Vec<u8>> = (0..3)
        .map(|k| std::fs::read(shard_path(&d, k)).expect("a shard"))
        .collect();
    // As an older rtpipe left it.
    std::fs::remove_file(d.join(KEPT)).expect("remove");
    let old = format!("# written by an older rtpipe\n{CONFIG}");
    std::fs::write(d.join(LEGACY_KEPT), &old).expect("write");
    let cfg = config::parse("t.toml", CONFIG).expect("a valid config");
    let found = survey(&d, &cfg, Part::ALL).expect("a survey");
    assert!(
        found.legacy && !found.kept && found.done.len() == 3,
        "{found:?}"
    );
    assert!(d.join(LEGACY_KEPT).exists(), "a survey changes nothing");
    let s = go(&d);
    assert_eq!((s.written, s.skipped), (0, 3), "its shards are kept");
    assert!(!d.join(LEGACY_KEPT).exists(), "replaced");
    let (_, _, kv) = parquet(&d.join(KEPT));
    let text = kv.iter().find(|(k, _)| k == "rtpipe.config");
    assert_eq!(
        text.and_then(|(_, v)| v.as_deref()),
        Some(old.as_str()),
        "its text as it was"
    );
    for (k, bytes) in shards.iter().enumerate() {
        assert_eq!(
            &std::fs::read(shard_path(&d, k as u64)).expect("a shard"),
            bytes
        );
    }
    assert_eq!(go(&d).skipped, 3);
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn an_older_folder_of_another_campaign_is_refused_and_left() {
    let d = dir("legacy-foreign");
    std::fs::create_dir_all(&d).expect("a folder");
    let theirs = CONFIG.replace("seed = 3", "seed = 4");
    std::fs::write(d.join(LEGACY_KEPT), &theirs).expect("write");
    let e = go_with(CONFIG, &d).expect_err("another campaign");
    assert!(e.message.contains("another campaign"), "{}", e.message);
    assert_eq!(names(&d), [LEGACY_KEPT], "nothing written");
    assert_eq!(
        std::fs::read_to_string(d.join(LEGACY_KEPT)).ok(),
        Some(theirs)
    );
    // Not a configuration at all: refused with its name.
    std::fs::write(d.join(LEGACY_KEPT), "hello").expect("write");
    let e = go_with(CONFIG, &d).expect_err("not a campaign file");
    assert!(
        e.message
            .contains("_campaign.toml, which is not a campaign configuration"),
        "{}",
        e.message
    );
    let _ = std::fs::remove_dir_all(d);
}
