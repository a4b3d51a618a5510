//! The pieces every HTML report of the command line shares: escaping, the
//! page's style (A4, small type, ruled tables), its head, and a figure as
//! inline SVG, so a report is one self-contained file (no external resource).

/// `text` with HTML's special characters escaped.
pub fn esc(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The page's style: A4, small type, tables with rules.
pub const STYLE: &str = "@page { size: A4; margin: 12mm; }\n\
body { font-family: 'DejaVu Sans', sans-serif; font-size: 9pt; margin: 0 auto; max-width: 186mm; color: #000; }\n\
h1 { font-size: 14pt; margin: 0 0 4pt; } h2 { font-size: 11pt; margin: 10pt 0 3pt; }\n\
table { border-collapse: collapse; width: 100%; } th, td { border-bottom: 1px solid #bbb; padding: 1.5pt 4pt; text-align: left; }\n\
td.n { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }\n\
p.note { margin: 2pt 0; } svg { width: 100%; height: auto; } figure { margin: 4pt 0; break-inside: avoid; }\n";

/// The page's opening up to its first heading: the document type, the
/// `title` (plain text, escaped here), the style and `<h1>title</h1>`.
pub fn page_start(title: &str) -> String {
    let t = esc(title);
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>{t}</title>\n<style>\n{STYLE}</style></head><body>\n<h1>{t}</h1>\n"
    )
}

/// The page's end.
pub const PAGE_END: &str = "</body></html>\n";

/// `fig` drawn as SVG inside a `<figure>`, to sit inline in the page; the
/// error names the report's figure.
pub fn figure(fig: &plot::Figure) -> Result<String, String> {
    let svg = plot::render_svg(fig).map_err(|e| format!("the report's figure: {e}"))?;
    Ok(format!("<figure>{}</figure>\n", strip_xml_decl(&svg)))
}

/// A number cell (right-aligned): `text`, escaped.
pub fn num(text: &str) -> String {
    format!("<td class=\"n\">{}</td>", esc(text))
}

/// An SVG document without its XML declaration, to sit inline in HTML.
pub fn strip_xml_decl(svg: &str) -> &str {
    match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Markup in a text is shown, not obeyed; the head holds the A4 style.
    #[test]
    fn text_is_escaped_and_the_page_prints_on_a4() {
        assert_eq!(esc("a<b & \"c\">"), "a&lt;b &amp; &quot;c&quot;&gt;");
        let head = page_start("x < y");
        assert!(head.contains("<title>x &lt; y</title>") && head.contains("<h1>x &lt; y</h1>"));
        assert!(head.contains("@page { size: A4"));
        assert_eq!(strip_xml_decl("<?xml version=\"1.0\"?>\n<svg a>"), "<svg a>");
        assert_eq!(num("1 < 2"), "<td class=\"n\">1 &lt; 2</td>");
    }
}
