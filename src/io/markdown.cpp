// The Markdown input reference: a generic renderer of a Schema (one section per table, one row per
// key) and the simulation input's reference, docs/input.md (the schema of io/config.cpp followed
// by the constitutive laws of the materials registry).
#include <fmt/format.h>

#include <string>

#include "law_keys.hpp"
#include "mpmcd/io/load_config.hpp"
#include "mpmcd/io/schema.hpp"
#include "mpmcd/materials/law.hpp"

namespace mpmcd::io {

std::string markdown_cell(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '|')
      out += "\\|";
    else if (c == '\n')
      out += ' ';
    else
      out += c;
  }
  return out;
}

std::string schema_markdown(const Schema& schema) {
  std::string md = "# " + schema.title + "\n\n";
  if (!schema.description.empty()) md += schema.description + "\n\n";
  for (const auto& t : schema.tables) {
    md += "## " + (t.header.empty() ? std::string("Top level") : "`" + t.header + "`") + "\n\n";
    if (!t.description.empty()) md += t.description + "\n\n";
    if (!t.keys.empty()) {
      md += "| key | type | default | range / allowed | unit | description |\n";
      md += "|---|---|---|---|---|---|\n";
      for (const auto& k : t.keys) {
        const std::string path = t.path.empty() ? k.name : t.path + "." + k.name;
        const std::string def = k.required               ? "**required**"
                                : k.default_text.empty() ? "–"
                                                         : "`" + k.default_text + "`";
        const std::string unit = (k.unit.empty() || k.unit == "-") ? "–" : k.unit;
        const std::string range = range_text(k).empty() ? "–" : range_text(k);
        md += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", path, markdown_cell(type_text(k)),
                          markdown_cell(def), markdown_cell(range), markdown_cell(unit),
                          markdown_cell(k.description));
      }
      md += "\n";
    }
    if (!t.extra_keys.empty()) md += t.extra_keys + "\n\n";
  }
  while (md.size() >= 2 && md[md.size() - 1] == '\n' && md[md.size() - 2] == '\n') md.pop_back();
  return md;
}

std::string input_reference_markdown() {
  std::string md = schema_markdown(config_schema());
  md += "\n## Constitutive laws\n\n";
  md +=
      "`materials[].law` is one of the laws below; the `[[materials]]` table then holds "
      "exactly that law's parameters (all required).\n";
  for (const auto& law : materials::law_registry()) {
    md += fmt::format("\n### `{}`\n\n{}\n\n", law.name, law.description);
    md += "| parameter | type | range | unit | description |\n|---|---|---|---|---|\n";
    for (const auto& k : law_keys(law))
      md += fmt::format("| `{}` | {} | {} | {} | {} |\n", k.name, type_text(k),
                        markdown_cell(range_text(k)), markdown_cell(k.unit),
                        markdown_cell(k.description));
  }
  return md;
}

}  // namespace mpmcd::io
