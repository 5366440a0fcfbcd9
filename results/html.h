// A small HTML report builder: sections, tables, figures, preformatted text. Self-contained pages (inline CSS,
// images by relative path), so a report folder can be zipped and sent.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace hovs::results {

std::string HtmlEscape(const std::string& s);

class HtmlPage {
 public:
  explicit HtmlPage(std::string title);
  HtmlPage& Heading(const std::string& text, int level = 2);
  HtmlPage& Paragraph(const std::string& text);  // escaped
  HtmlPage& Table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows);
  // A paragraph: `before`, then a link to `href` (relative to the page) reading `text`, then `after`; escaped.
  HtmlPage& Link(const std::string& before, const std::string& href, const std::string& text,
                 const std::string& after = "");
  HtmlPage& Figure(const std::string& src, const std::string& caption, int width_px = 0);
  HtmlPage& Preformatted(const std::string& text);
  std::string Render() const;

 private:
  std::string title_;
  std::string body_;
};

// Versions of hovs and the libraries of the core and results layers (adds VTK).
std::map<std::string, std::string> ResultsVersions();

}  // namespace hovs::results
