// The confusion table of a diagnosis sweep (issue 20; bench/diagnose/confusion.sh): rows are the
// injected effects, columns the effects the diagnosis named (on any axis), a cell the runs that
// named it and, in parentheses, those whose finding listed the injected effect as not told apart;
// plus per-row counters (no finding, something unexplained, …). Written as Markdown.
#pragma once
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "calibration/diagnosis/diagnose.hpp"

namespace calbench {

class ConfusionTable {
 public:
  explicit ConfusionTable(std::vector<std::string> counters) : counter_names_(std::move(counters)) {}
  void add_row(const std::string& name) {
    rows_.push_back(name);
    cells_.emplace_back();
    counters_.emplace_back(counter_names_.size(), 0);
  }
  // One run of the last row: its findings against the injected effect.
  void add_run(const std::vector<DiagFinding>& findings, EffectId truth) {
    std::map<std::string, bool> named;  // effect → the truth listed as its alternative
    for (const auto& f : findings) {
      bool& alt = named[effect_name(f.term.effect)];
      for (const auto& a : f.alternatives) alt = alt || a.term.effect == truth;
    }
    for (const auto& [e, alt] : named) {
      auto& c = cells_.back()[e];
      c.first += 1;
      c.second += alt;
      if (std::find(cols_.begin(), cols_.end(), e) == cols_.end()) cols_.push_back(e);
    }
  }
  void count(std::size_t counter, bool yes) { counters_.back()[counter] += yes; }

  std::string markdown(const std::string& title) const {
    std::vector<std::string> cols = cols_;
    std::sort(cols.begin(), cols.end());
    std::string md = "\n### " + title + "\n\n| injected |";
    for (const auto& c : cols) md += " `" + c + "` |";
    for (const auto& c : counter_names_) md += " " + c + " |";
    md += "\n|---|";
    for (std::size_t c = 0; c < cols.size() + counter_names_.size(); ++c) md += "---|";
    md += "\n";
    for (std::size_t i = 0; i < rows_.size(); ++i) {
      md += "| " + rows_[i] + " |";
      for (const auto& c : cols) {
        const auto it = cells_[i].find(c);
        md += it == cells_[i].end() ? " |"
                                    : " " + std::to_string(it->second.first) +
                                          (it->second.second ? " (" + std::to_string(it->second.second) + " alt)" : "") + " |";
      }
      for (int n : counters_[i]) md += " " + std::to_string(n) + " |";
      md += "\n";
    }
    return md;
  }

  // Appends the table to DIAGNOSE_CONFUSION_OUT, or prints it.
  static void emit(const std::string& md) {
    if (const char* out = std::getenv("DIAGNOSE_CONFUSION_OUT")) {
      if (std::FILE* f = std::fopen(out, "a")) {
        std::fputs(md.c_str(), f);
        std::fclose(f);
      }
    } else {
      std::printf("%s\n", md.c_str());
    }
  }

 private:
  std::vector<std::string> counter_names_, rows_, cols_;
  std::vector<std::map<std::string, std::pair<int, int>>> cells_;
  std::vector<std::vector<int>> counters_;
};

}  // namespace calbench
