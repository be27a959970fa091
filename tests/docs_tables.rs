//! Numbers in docs that cannot drift: every table docs/ marks as generated
//! (`<!-- generated: scg study cyclone|loading --from DIR --markdown ... -->` up to
//! `<!-- end of generated -->`) equals what the command prints from the committed summary.
//!
//! Run: `cargo test --release --test docs_tables`; after a rerun of the study, copy its
//! summary.json to the folder the marker names and paste the command's output.

mod common;

#[test]
fn the_cyclone_tables_are_the_studys_output() {
    let doc = std::fs::read_to_string(common::repo("docs/cyclone.md")).unwrap();
    let marker = "<!-- generated: scg study cyclone --from ";
    let mut found = 0;
    for block in doc.split(marker).skip(1) {
        let dir = block.split_whitespace().next().unwrap();
        let body = &block[block.find("-->").unwrap() + 4..];
        let body = &body[..body
            .find("<!-- end of generated -->")
            .expect("an end marker")];
        let runs = scg::cli::study::cyclone::read_study(&common::repo(dir)).expect(dir);
        let expect = scg::cli::study::cyclone::markdown(&runs);
        assert_eq!(
            body, expect,
            "docs/cyclone.md's table from {dir} differs from `scg study cyclone --from {dir} --markdown`"
        );
        found += 1;
    }
    assert!(found >= 1, "no generated table in docs/cyclone.md");
}

/// The loading study's table in docs/performance.md is `scg study loading --from DIR
/// --markdown` of the committed summary.
#[test]
fn the_loading_table_is_the_studys_output() {
    let doc = std::fs::read_to_string(common::repo("docs/performance.md")).unwrap();
    let marker = "<!-- generated: scg study loading --from ";
    let mut found = 0;
    for block in doc.split(marker).skip(1) {
        let dir = block.split_whitespace().next().unwrap();
        let body = &block[block.find("-->").unwrap() + 4..];
        let body = &body[..body
            .find("<!-- end of generated -->")
            .expect("an end marker")];
        let (records, duration) =
            scg::cli::study::loading::read_study(&common::repo(dir)).expect(dir);
        assert_eq!(
            body,
            scg::cli::study::loading::markdown(&records, duration),
            "docs/performance.md's table from {dir} differs from `scg study loading --from {dir} --markdown`"
        );
        found += 1;
    }
    assert!(found >= 1, "no generated table in docs/performance.md");
}

/// `--markdown` prints a finished study only: without `--from`, or with `--run`, it is bad
/// input (exit 2), and other studies refuse it.
#[test]
fn markdown_needs_a_finished_study() {
    use scg::cli::study::StudyArgs;
    let args = |from: Option<&str>, run: Option<&str>, study: &str| StudyArgs {
        study: study.into(),
        quick: false,
        out: None,
        no_record: true,
        set: Vec::new(),
        openfoam: None,
        from: from.map(common::repo),
        run: run.map(str::to_string),
        cg_feed: 1.0,
        markdown: true,
        loadings: None,
    };
    let local = scg::cli::points::Local;
    assert_eq!(
        scg::cli::study::study(args(None, None, "cyclone"), &local),
        2
    );
    assert_eq!(
        scg::cli::study::study(
            args(Some("docs/data/cyclone-study"), Some("scg2"), "cyclone"),
            &local
        ),
        2
    );
    assert_eq!(
        scg::cli::study::study(args(None, None, "classifier"), &local),
        2
    );
    assert_eq!(
        scg::cli::study::study(
            args(Some("docs/data/cyclone-study"), None, "cyclone"),
            &local
        ),
        0
    );
    // the loading study: --from needs --markdown, and a folder with its summary
    let mut a = args(Some("docs/data/loading-study"), None, "loading");
    a.markdown = false;
    assert_eq!(scg::cli::study::study(a, &local), 2);
    assert_eq!(
        scg::cli::study::study(
            args(Some("docs/data/cyclone-study"), None, "loading"),
            &local
        ),
        2
    );
    assert_eq!(
        scg::cli::study::study(
            args(Some("docs/data/loading-study"), None, "loading"),
            &local
        ),
        0
    );
}
