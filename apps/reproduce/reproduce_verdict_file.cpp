#include "apps/reproduce/reproduce_verdict_file.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "apps/reproduce/reproduce_report.h"
#include "apps/reproduce/reproduce_verdict.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_io.h"
#include "sim/version.h"

namespace uavsim::sim {

namespace fs = std::filesystem;
using core::Json;
using Claim = ReproduceClaim;
using Block = ReportBlock;
using Document = ReportDocument;

void WriteVerdicts(const std::string& dir, double fraction, const std::string& provenance,
                   std::vector<Claim>& claims, Document& doc, std::size_t protocol,
                   std::size_t summary_at, const std::string& title) {
  JudgeClaims(dir, fraction, claims);
  std::string& p = doc.blocks.at(protocol).text;
  p = p.substr(0, p.find(" Verdicts compare methods")) + " " +
      VerdictRuleText(claims, fraction, provenance);
  const std::vector<Block> summary = VerdictBlocks(claims);
  doc.blocks.insert(doc.blocks.begin() + static_cast<std::ptrdiff_t>(summary_at), summary.begin(),
                    summary.end());
  for (const Block& b : ComparisonBlocks(claims)) doc.blocks.push_back(b);
  core::WriteFileAtomic((fs::path(dir) / "claims.csv").string(), ClaimsCsv(claims));
  core::WriteFileAtomic((fs::path(dir) / "report.md").string(), RenderMarkdown(title, doc));
  core::WriteFileAtomic((fs::path(dir) / "report.html").string(), RenderHtml(title, doc));
}

namespace {

// The claims' texts as the report wrote them (claims.csv writes ';' for
// ','): artefact, claim, ours, a criterion's detail and the frame split's
// verdict, from the verdict table of report.md, row by row.
void TextsFromReport(const std::string& md_file, const Block& table, std::vector<Claim>& claims) {
  if (table.rows.size() != claims.size() + 1 || table.rows[0].size() < 4)
    throw core::UsageError(md_file + ": the verdict table has " +
                           std::to_string(table.rows.size() - 1) + " claims, claims.csv " +
                           std::to_string(claims.size()));
  const auto clean = [](std::string s) {
    std::replace(s.begin(), s.end(), ',', ';');
    return s;
  };
  for (std::size_t k = 0; k < claims.size(); ++k) {
    const std::vector<std::string>& row = table.rows[k + 1];
    Claim& c = claims[k];
    if (clean(row[0]) != c.artefact || clean(row[1]) != c.paper)
      throw core::UsageError(md_file + ": the verdict table's row " + std::to_string(k + 1) + " (" +
                             row[0] + ") is not claims.csv's claim " + std::to_string(k + 1) +
                             " (" + c.artefact + ")");
    c.artefact = row[0], c.paper = row[1], c.ours = row[2];
    if (c.comparisons.empty() && row[3].rfind(c.verdict + ": ", 0) == 0)
      c.detail = row[3].substr(c.verdict.size() + 2);
    const bool frame = std::any_of(c.comparisons.begin(), c.comparisons.end(),
                                   [](const ClaimComparison& x) { return x.frame; });
    const std::string& f = row.back();
    if (frame || f == "-" || table.rows[0].back() != "frame split") continue;
    // Its comparisons are not in claims.csv: the verdict stays as written.
    const std::string why =
        "by the earlier three-outcome rule: its comparisons are not in "
        "claims.csv";
    c.frame_verdict = !f.empty() && f.back() == ')' ? f.substr(0, f.size() - 1) + "; " + why + ")"
                                                    : f + " (" + why + ")";
    if (f.find(why) != std::string::npos) c.frame_verdict = f;
  }
}

}  // namespace

void RedrawReproduceReport(const std::string& dir) {
  const std::string md_file = (fs::path(dir) / "report.md").string();
  std::vector<Claim> claims = ReadClaimsCsv((fs::path(dir) / "claims.csv").string());
  std::string title;
  Document doc;
  try {
    doc = ParseMarkdown(core::ReadFileBytes(md_file), &title);
  } catch (const std::invalid_argument& e) {
    throw core::UsageError(md_file + ": " + e.what());
  }
  const std::size_t verdicts = doc.FindHeading("Verdicts");
  std::size_t table = verdicts;
  while (table < doc.NextHeading(verdicts) && doc.blocks[table].kind != Block::kTable) ++table;
  if (verdicts == doc.blocks.size() || table == doc.NextHeading(verdicts))
    throw core::UsageError(md_file + ": no verdict table (\"## Verdicts\")");
  TextsFromReport(md_file, doc.blocks[table], claims);
  doc.blocks.erase(doc.blocks.begin() + static_cast<std::ptrdiff_t>(verdicts),
                   doc.blocks.begin() + static_cast<std::ptrdiff_t>(doc.NextHeading(verdicts)));
  const std::size_t every = doc.FindHeading("Every comparison");
  if (every < doc.blocks.size())
    doc.blocks.erase(doc.blocks.begin() + static_cast<std::ptrdiff_t>(every),
                     doc.blocks.begin() + static_cast<std::ptrdiff_t>(doc.NextHeading(every)));
  std::size_t protocol = 0;
  while (protocol < verdicts && doc.blocks[protocol].text.rfind("Protocol: ", 0) != 0) ++protocol;
  if (protocol == verdicts) throw core::UsageError(md_file + ": no protocol paragraph");

  // The margin rule: the plan record's when DIR has one, else this binary's.
  double fraction = kEquivalenceFraction;
  bool recorded = false;
  const fs::path record = fs::path(dir) / "reproduce.json";
  std::error_code ec;
  if (fs::is_regular_file(record, ec)) {
    const Json r = core::LoadJsonFile(record.string());
    if (r.contains("equivalence_fraction") && r["equivalence_fraction"].is_number())
      fraction = r["equivalence_fraction"].get<double>(), recorded = true;
  }
  const std::string note =
      std::string("Verdicts redrawn by `uavsim report DIR` (uavsim ") + Version() + ", " +
      GitHash() +
      ") from this folder's claims.csv and artefact tables, without re-running any training: "
      "the figures and tables below are those the trainings' report wrote; the margin rule is " +
      (recorded ? "the plan record's (reproduce.json)."
                : "this binary's (the folder has no plan record of one), not one recorded before "
                  "the trainings.");
  Block& next = doc.blocks.at(protocol + 1);
  std::size_t summary_at = verdicts;
  if (next.kind == Block::kText && next.text.rfind("Verdicts redrawn", 0) == 0) {
    next.text = note;
  } else {
    doc.blocks.insert(doc.blocks.begin() + static_cast<std::ptrdiff_t>(protocol + 1),
                      {Block::kText, note, "", {}});
    ++summary_at;
  }
  WriteVerdicts(dir, fraction,
                recorded ? kRecordedRule
                         : "of the binary that redrew this report, set after these trainings "
                           "(next paragraph)",
                claims, doc, protocol, summary_at, title);
}

}  // namespace uavsim::sim
