#include "results/plot.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "results/csv.h"
#include "results/gnuplot.h"

namespace uavsim::results {
namespace {

namespace fs = std::filesystem;

struct Series {
  std::string name;
  std::string points;  // "x y\n" lines ("x y half-width\n" with error bars)
};

}  // namespace

std::string PlotCsv(const std::string& csv_path, const PlotSpec& spec) {
  const std::string where = "plot " + csv_path + ": ";
  const std::string png =
      spec.png_path.empty() ? fs::path(csv_path).replace_extension(".png").string() : spec.png_path;

  CsvFile csv;
  if (std::string err = ReadCsvFile(csv_path, &csv); !err.empty()) return where + err;
  const auto column = [&csv](const std::string& name) { return csv.Column(name); };
  const long xc = column(spec.x_column), yc = column(spec.y_column);
  const long gc = spec.group_column.empty() ? -2 : column(spec.group_column);
  if (xc < 0) return where + "no column \"" + spec.x_column + "\"";
  if (yc < 0) return where + "no column \"" + spec.y_column + "\"";
  if (gc == -1) return where + "no column \"" + spec.group_column + "\"";
  const long ebc = spec.y_error_column.empty() ? -2 : column(spec.y_error_column);
  if (ebc == -1) return where + "no column \"" + spec.y_error_column + "\"";

  std::vector<Series> series;
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
    for (auto& candidate : series)
      if (candidate.name == group) s = &candidate;
    if (!s) {
      series.push_back({group, ""});
      s = &series.back();
    }
    s->points += ShortestNumber(x) + " " + ShortestNumber(y);
    if (ebc >= 0) s->points += " " + ShortestNumber(half_width);
    s->points += "\n";
  }
  if (series.empty()) return where + "no data rows";

  // Texts go through variables: `set title` and `title` take a string
  // expression there.
  std::ostringstream gp;
  gp << "uavsim_title = " << GnuplotString(spec.title) << "\n"
     << "uavsim_xlabel = " << GnuplotString(spec.x_label) << "\n"
     << "uavsim_ylabel = " << GnuplotString(spec.y_label) << "\n";
  for (std::size_t i = 0; i < series.size(); ++i)
    gp << "uavsim_line" << i << " = " << GnuplotString(series[i].name) << "\n";
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
  if (ebc >= 0) gp << "set offsets graph 0.03, graph 0.03, 0, 0\n";
  for (std::size_t i = 0; i < series.size(); ++i)
    gp << "$g" << i << " << EOD\n" << series[i].points << "EOD\n";
  gp << "plot ";
  for (std::size_t i = 0; i < series.size(); ++i)
    gp << (i ? ", \\\n     " : "") << "$g" << i
       << (ebc >= 0 ? " using 1:2:3 with yerrorlines" : " using 1:2 with linespoints")
       << " title uavsim_line" << i;
  gp << "\n";
  GnuplotImage image;
  image.png_path = png;
  image.width_px = spec.width_px;
  image.height_px = spec.height_px;
  image.font.clear();
  image.gnuplot = spec.gnuplot;
  if (std::string failure = RunGnuplot(gp.str(), image); !failure.empty()) return where + failure;
  return "";
}

}  // namespace uavsim::results
