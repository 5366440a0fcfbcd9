#include "results/html.h"

#include <vtkVersion.h>

#include "core/version.h"

namespace hovs::results {

std::string HtmlEscape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char ch : s) {
    switch (ch) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += ch;
    }
  }
  return out;
}

HtmlPage::HtmlPage(std::string title) : title_(std::move(title)) {}

HtmlPage& HtmlPage::Heading(const std::string& text, int level) {
  const std::string l = std::to_string(level < 1 ? 1 : level > 4 ? 4 : level);
  body_ += "<h" + l + ">" + HtmlEscape(text) + "</h" + l + ">\n";
  return *this;
}

HtmlPage& HtmlPage::Paragraph(const std::string& text) {
  body_ += "<p>" + HtmlEscape(text) + "</p>\n";
  return *this;
}

HtmlPage& HtmlPage::Link(const std::string& before, const std::string& href, const std::string& text,
                         const std::string& after) {
  body_ += "<p>" + HtmlEscape(before) + "<a href=\"" + HtmlEscape(href) + "\">" + HtmlEscape(text) + "</a>" +
           HtmlEscape(after) + "</p>\n";
  return *this;
}

HtmlPage& HtmlPage::Table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  body_ += "<table>\n<tr>";
  for (const auto& h : header) body_ += "<th>" + HtmlEscape(h) + "</th>";
  body_ += "</tr>\n";
  for (const auto& row : rows) {
    body_ += "<tr>";
    for (const auto& cell : row) body_ += "<td>" + HtmlEscape(cell) + "</td>";
    body_ += "</tr>\n";
  }
  body_ += "</table>\n";
  return *this;
}

HtmlPage& HtmlPage::Figure(const std::string& src, const std::string& caption, int width_px) {
  body_ += "<figure><img src=\"" + HtmlEscape(src) + "\"" +
           (width_px > 0 ? " width=\"" + std::to_string(width_px) + "\"" : std::string()) + " alt=\"" +
           HtmlEscape(caption) + "\"><figcaption>" + HtmlEscape(caption) + "</figcaption></figure>\n";
  return *this;
}

HtmlPage& HtmlPage::Preformatted(const std::string& text) {
  body_ += "<pre>" + HtmlEscape(text) + "</pre>\n";
  return *this;
}

std::string HtmlPage::Render() const {
  return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + HtmlEscape(title_) +
         "</title>\n<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
         "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;"
         "text-align:right}th{background:#eee}td:first-child,th:first-child{text-align:left}"
         "figure{display:inline-block;margin:0.5em}figcaption{font-size:90%;color:#555}"
         "pre{background:#f6f6f6;padding:0.7em;overflow-x:auto}</style></head>\n<body>\n<h1>" +
         HtmlEscape(title_) + "</h1>\n" + body_ + "</body></html>\n";
}

std::map<std::string, std::string> ResultsVersions() {
  auto v = CoreVersions();
  v["vtk"] = vtkVersion::GetVTKVersion();
  return v;
}

}  // namespace hovs::results
