use super::*;
use rtpipe_testkit::Scratch;

fn every_kind() -> Vec<Column> {
    vec![
        Column::new("u", Kind::UInt),
        Column::new("n", Kind::Count),
        Column::new("f", Kind::Float),
        Column::new("b", Kind::Bool),
        Column::new("t", Kind::Text),
        Column::new("i", Kind::Int),
        Column::new("o", Kind::OptInt),
    ]
}

fn table(rows: &[(u64, Option<i64>)]) -> Table {
    let Ok(mut t) = Table::new("t", every_kind()) else {
        unreachable!("distinct names");
    };
    for &(u, o) in rows {
        t.push(vec![
            Cell::UInt(u),
            Cell::UInt(3),
            Cell::Float(0.5),
            Cell::Bool(true),
            Cell::from("x"),
            Cell::Int(-7),
            Cell::opt_int(o),
        ]);
    }
    t
}

#[test]
fn the_schema_has_a_typed_field_per_column() {
    let text = schema("m", &every_kind());
    assert!(text.starts_with("message m {\n"), "{text}");
    assert!(
        text.contains("REQUIRED INT64 u (INTEGER(64,false));"),
        "{text}"
    );
    assert!(text.contains("OPTIONAL INT64 o;"), "{text}");
    assert!(parse_message_type(&text).is_ok(), "{text}");
}

#[test]
fn row_groups_and_the_footer_read_back() {
    let file = Scratch::new("parquet-round-trip").within("t.parquet");
    let mut f = std::fs::File::create(&file).expect("a file");
    let kv = [("k", "v".to_string()), ("n", "2".to_string())];
    let mut w = TableWriter::new(&mut f, "m", &every_kind(), "test", &kv).expect("a writer");
    w.row_group(&table(&[(u64::MAX, Some(1)), (0, None)]))
        .expect("a group");
    w.row_group(&table(&[])).expect("nothing");
    w.row_group(&table(&[(5, None)])).expect("a group");
    w.finish().expect("the footer");
    drop(f);
    let footer = read_footer(&file).expect("a footer");
    assert_eq!(footer.rows, 3);
    assert_eq!(footer.row_groups, [2, 1]);
    assert_eq!(footer.get("k"), Some("v"));
    assert_eq!(footer.get("n"), Some("2"));
    assert_eq!(footer.get("missing"), None);
    assert_eq!(footer.columns, ["u", "n", "f", "b", "t", "i", "o"]);
    let reader =
        SerializedFileReader::new(std::fs::File::open(&file).expect("open")).expect("a reader");
    let rows: Vec<String> = (reader.get_row_iter(None).expect("rows"))
        .map(|r| r.expect("a row").to_string())
        .collect();
    assert_eq!(rows.len(), 3);
    assert!(rows[0].contains("u: 18446744073709551615"), "{}", rows[0]);
    assert!(rows[0].contains("o: 1"), "{}", rows[0]);
    assert!(rows[1].contains("o: null"), "{}", rows[1]);
}

#[test]
fn a_file_that_is_not_parquet_has_no_footer() {
    let file = Scratch::new("parquet-not").within("x.parquet");
    std::fs::write(&file, "not parquet").expect("a file");
    let e = read_footer(&file).err().unwrap_or_default();
    assert!(e.starts_with("has no Parquet footer"), "{e}");
    let e = read_footer(&file.with_extension("gone"))
        .err()
        .unwrap_or_default();
    assert!(e.starts_with("cannot be opened"), "{e}");
}
