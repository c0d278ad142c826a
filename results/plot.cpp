#include "results/plot.h"

#include <filesystem>
#include <string>
#include <vector>

#include "results/csv.h"
#include "results/gnuplot.h"
#include "results/gnuplot_figure.h"

namespace uavsim::results {
namespace {

namespace fs = std::filesystem;

struct Series {
  std::string name;
  std::string points;  // "x y\n" lines ("x y half-width\n" with error bars)
};

// The columns PlotCsv reads: -2 = not asked for.
struct Columns {
  long x = -1, y = -1, group = -2, error = -2;
};

// The columns of `spec` in `csv` into `c`: "" or the one missing (after
// `where`).
std::string FindColumns(const CsvFile& csv, const PlotSpec& spec, const std::string& where,
                        Columns* c) {
  const auto column = [&csv](const std::string& name) { return csv.Column(name); };
  c->x = column(spec.x_column);
  c->y = column(spec.y_column);
  c->group = spec.group_column.empty() ? -2 : column(spec.group_column);
  if (c->x < 0) return where + "no column \"" + spec.x_column + "\"";
  if (c->y < 0) return where + "no column \"" + spec.y_column + "\"";
  if (c->group == -1) return where + "no column \"" + spec.group_column + "\"";
  c->error = spec.y_error_column.empty() ? -2 : column(spec.y_error_column);
  if (c->error == -1) return where + "no column \"" + spec.y_error_column + "\"";
  return "";
}

// The rows of `csv` as series in first-seen order: "" or why not (after
// `where`).
std::string ReadSeries(const CsvFile& csv, const PlotSpec& spec, const Columns& c,
                       const std::string& where, std::vector<Series>* series) {
  const long xc = c.x, yc = c.y, gc = c.group, ebc = c.error;
  for (std::size_t r = 0; r < csv.rows.size(); ++r) {
    const std::vector<std::string>& cells = csv.rows[r];
    const std::string at = where + "line " + std::to_string(csv.line[r]) + ": ";
    double x = 0.0, y = 0.0, half_width = 0.0;
    const bool y_missing = spec.skip_empty_y && cells[yc].empty();
    if (!ParseFiniteNumber(cells[xc], &x) || (!y_missing && !ParseFiniteNumber(cells[yc], &y)))
      return at + "expected finite numbers in \"" + spec.x_column + "\" and \"" + spec.y_column +
             "\"";
    if (spec.log_x && x <= 0.0) return at + "x must be > 0 on a logarithmic axis";
    if (spec.log_y && !y_missing && y <= 0.0) return at + "y must be > 0 on a logarithmic axis";
    if (ebc >= 0 && !cells[ebc].empty() &&
        (!ParseFiniteNumber(cells[ebc], &half_width) || half_width < 0))
      return at + "expected an empty cell or a finite number >= 0 in \"" + spec.y_error_column +
             "\"";
    if (y_missing) continue;
    const std::string group = gc >= 0 ? cells[gc] : spec.y_column;
    Series* s = nullptr;
    for (auto& candidate : *series)
      if (candidate.name == group) s = &candidate;
    if (!s) {
      series->push_back({group, ""});
      s = &series->back();
    }
    s->points += ShortestNumber(x) + " " + ShortestNumber(y);
    if (ebc >= 0) s->points += " " + ShortestNumber(half_width);
    s->points += "\n";
  }
  if (series->empty()) return where + "no data rows";
  return "";
}

// Texts go through variables: `set title` and `title` take a string
// expression there.
void WriteLinePlot(GnuplotFigure& figure, const PlotSpec& spec, const std::vector<Series>& series,
                   bool error_bars) {
  figure.Text("uavsim_title", spec.title);
  figure.Text("uavsim_xlabel", spec.x_label);
  figure.Text("uavsim_ylabel", spec.y_label);
  for (std::size_t i = 0; i < series.size(); ++i)
    figure.Text("uavsim_line" + std::to_string(i), series[i].name);
  std::ostream& gp = figure.Commands();
  gp << "set datafile separator whitespace\n"
     << "set title uavsim_title\n"
     << "set xlabel uavsim_xlabel\n"
     << "set ylabel uavsim_ylabel\n"
     << "set grid\n"
     << (spec.key_below ? "set key below\n" : "set key top left\n");
  if (spec.log_x) gp << "set logscale x\n";
  if (spec.log_y) gp << "set logscale y\n";
  if (spec.y_min_zero && !spec.log_y) gp << "set yrange [0:*]\n";
  // Error bars at the ends of the x range would be drawn on the border.
  if (error_bars) gp << "set offsets graph 0.03, graph 0.03, 0, 0\n";
  for (std::size_t i = 0; i < series.size(); ++i) {
    figure.Data("g" + std::to_string(i), series[i].points);
    figure.Curve("$g" + std::to_string(i) +
                 (error_bars ? " using 1:2:3 with yerrorlines" : " using 1:2 with linespoints") +
                 " title uavsim_line" + std::to_string(i));
  }
  figure.Plot();
}

}  // namespace

std::string PlotCsv(const std::string& csv_path, const PlotSpec& spec) {
  const std::string where = "plot " + csv_path + ": ";
  const std::string png =
      spec.png_path.empty() ? fs::path(csv_path).replace_extension(".png").string() : spec.png_path;

  CsvFile csv;
  if (std::string err = ReadCsvFile(csv_path, &csv); !err.empty()) return where + err;
  Columns columns;
  if (std::string err = FindColumns(csv, spec, where, &columns); !err.empty()) return err;
  std::vector<Series> series;
  if (std::string err = ReadSeries(csv, spec, columns, where, &series); !err.empty()) return err;

  GnuplotFigure figure;
  WriteLinePlot(figure, spec, series, columns.error >= 0);
  // No font: the terminal's default.
  const GnuplotImage image{png, spec.width_px, spec.height_px, "", spec.gnuplot};
  if (std::string failure = figure.Draw(image); !failure.empty()) return where + failure;
  return "";
}

}  // namespace uavsim::results
