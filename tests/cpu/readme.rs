//! The README and `docs/`: the usage snippet is `examples/minimal.rs`, and every picture and
//! relative link names a file (and a heading) that exists. `scripts/readme-images.sh`
//! regenerates the pictures.

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// examples/minimal.rs is the README's usage snippet, verbatim, after its harness lines.
#[test]
fn readme_snippet_is_the_minimal_example() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let start = readme.find("```rust\n").expect("README has a rust snippet") + 8;
    let end = start + readme[start..].find("```").unwrap();
    let snippet = &readme[start..end];
    let minimal = std::fs::read_to_string(root().join("examples/minimal.rs")).unwrap();
    let body = minimal
        .split_once("use common::DefaultPlugins;\n\n")
        .expect("minimal.rs has its harness line")
        .1;
    assert_eq!(
        body, snippet,
        "README snippet and examples/minimal.rs drifted apart"
    );
}

/// A Markdown link: `![alt](target)` (an image) or `[text](target)`, with its line.
#[derive(Debug, PartialEq)]
struct Link {
    image: bool,
    target: String,
    line: usize,
}

/// The links of a Markdown text, outside fenced code blocks and inline code spans.
fn markdown_links(text: &str) -> Vec<Link> {
    let mut links = Vec::new();
    let mut fenced = false;
    for (i, raw) in text.lines().enumerate() {
        if raw.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Inline code spans out (`[a](b)` in backticks is code, not a link).
        let line: String = raw
            .split('`')
            .enumerate()
            .map(|(k, part)| if k % 2 == 0 { part } else { "" })
            .collect::<Vec<_>>()
            .join(" ");
        let b = line.as_bytes();
        let mut from = 0;
        while let Some(at) = line[from..].find("](") {
            let close = from + at;
            from = close + 2;
            // The `[` that opens this `]`.
            let mut depth = 0i32;
            let mut open = None;
            for j in (0..close).rev() {
                match b[j] {
                    b']' => depth += 1,
                    b'[' if depth == 0 => {
                        open = Some(j);
                        break;
                    }
                    b'[' => depth -= 1,
                    _ => {}
                }
            }
            let Some(open) = open else { continue };
            let Some(len) = line[close + 2..].find(')') else {
                continue;
            };
            let inner = line[close + 2..close + 2 + len].trim();
            // `(path "title")` and `(<path>)`.
            let target = match inner.strip_prefix('<') {
                Some(rest) => rest.split('>').next().unwrap_or(""),
                None => inner.split_whitespace().next().unwrap_or(""),
            };
            links.push(Link {
                image: open > 0 && b[open - 1] == b'!',
                target: target.to_string(),
                line: i + 1,
            });
        }
    }
    links
}

/// GitHub's anchor of a heading: lower case, spaces to `-`, punctuation but `-` and `_` out.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a Markdown text's headings (outside code blocks).
fn anchors(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && line.starts_with('#') {
            out.push(slug(line.trim_start_matches('#')));
        }
    }
    out
}

/// What is wrong with the links of `file` (a Markdown file under the crate's root): missing
/// files, missing headings, images that are not images; plus how many images it shows.
fn check_links(file: &Path) -> (Vec<String>, usize) {
    let text = std::fs::read_to_string(file).unwrap();
    let rel = file
        .strip_prefix(root())
        .unwrap_or(file)
        .display()
        .to_string();
    let dir = file.parent().unwrap();
    let mut problems = Vec::new();
    let mut images = 0;
    for link in markdown_links(&text) {
        let t = &link.target;
        let at = format!("{rel}:{}", link.line);
        if t.is_empty() {
            problems.push(format!("{at}: empty link"));
            continue;
        }
        if t.contains("://") || t.starts_with("mailto:") {
            if link.image {
                problems.push(format!(
                    "{at}: remote image {t} (keep pictures in docs/images)"
                ));
            }
            continue;
        }
        let (path, anchor) = t.split_once('#').unwrap_or((t, ""));
        let target: PathBuf = if path.is_empty() {
            file.to_path_buf()
        } else {
            dir.join(path)
        };
        if !target.exists() {
            let kind = if link.image { "image" } else { "file" };
            problems.push(format!("{at}: missing {kind} {t}"));
            continue;
        }
        if link.image {
            images += 1;
            let ext = target.extension().and_then(|e| e.to_str()).unwrap_or("");
            if !["png", "jpg", "jpeg", "svg", "gif", "webp"].contains(&ext) {
                problems.push(format!("{at}: {t} is not an image"));
            }
        }
        if !anchor.is_empty() && target.extension().is_some_and(|e| e == "md") {
            let heads = anchors(&std::fs::read_to_string(&target).unwrap());
            if !heads.iter().any(|h| h == anchor) {
                problems.push(format!("{at}: no heading #{anchor} in {path} ({heads:?})"));
            }
        }
    }
    (problems, images)
}

/// README.md and every docs/*.md.
fn markdown_files() -> Vec<PathBuf> {
    let mut files = vec![root().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// Every picture (`![..](path)`) and every relative link of README.md and docs/*.md names a
/// file that exists (and a heading that exists, for `page.md#anchor`); the README shows the
/// showcase and the five techniques; no picture in docs/images is over 500 KB.
#[test]
fn readme_images_exist() {
    let mut problems = Vec::new();
    let mut readme_images = 0;
    for file in markdown_files() {
        let (p, images) = check_links(&file);
        if file.ends_with("README.md") {
            readme_images = images;
        }
        problems.extend(p);
    }
    assert!(
        problems.is_empty(),
        "broken links (scripts/readme-images.sh makes the pictures):\n{}",
        problems.join("\n")
    );
    assert!(
        readme_images >= 6,
        "the README shows {readme_images} pictures: expected the showcase and the five techniques"
    );
    for e in std::fs::read_dir(root().join("docs/images")).unwrap() {
        let e = e.unwrap();
        let size = e.metadata().unwrap().len();
        assert!(
            size < 500 * 1024,
            "{} is {size} bytes (keep pictures under 500 KB)",
            e.path().display()
        );
    }
}

/// The parser finds what a reader sees and nothing in code.
#[test]
fn readme_link_parser() {
    let md = "![a](x.png) and [b](y.md#h \"title\") `[c](z)`\n```\n[d](w)\n```\n| [e [f]](<v w.md>) |\n[g](https://x.y)";
    let links = markdown_links(md);
    let t: Vec<(bool, &str, usize)> = links
        .iter()
        .map(|l| (l.image, l.target.as_str(), l.line))
        .collect();
    assert_eq!(
        t,
        [
            (true, "x.png", 1),
            (false, "y.md#h", 1),
            (false, "v w.md", 5),
            (false, "https://x.y", 6)
        ]
    );
    assert_eq!(
        slug(" Invalid values and the GPU's limits"),
        "invalid-values-and-the-gpus-limits"
    );
    assert_eq!(
        slug(" AAPS (the `Aaps` technique)"),
        "aaps-the-aaps-technique"
    );
}
