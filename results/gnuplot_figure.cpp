#include "results/gnuplot_figure.h"

#include <string>
#include <vector>

#include "results/figure_style.h"
#include "results/gnuplot.h"

namespace uavsim::results {

std::string ScreenCoordinates::X(double px_from_left) const {
  return ShortestNumber(px_from_left / width_px);
}

std::string ScreenCoordinates::Y(double px_from_top) const {
  return ShortestNumber(1.0 - px_from_top / height_px);
}

void GnuplotFigure::Text(const std::string& variable, const std::string& text) {
  script_ << variable << " = " << GnuplotString(text) << "\n";
}

void GnuplotFigure::TextLines(const std::string& variable, const std::vector<std::string>& lines) {
  script_ << variable << " = " << GnuplotLines(lines) << "\n";
}

void GnuplotFigure::Data(const std::string& name, const std::string& rows) {
  script_ << "$" << name << " << EOD\n" << rows << "EOD\n";
}

void GnuplotFigure::Curve(const std::string& curve) { curves_.push_back(curve); }

void GnuplotFigure::Plot(CurveLayout layout) {
  const char* separator = layout == CurveLayout::kOnePerLine ? ", \\\n     " : ", ";
  script_ << "plot ";
  for (std::size_t i = 0; i < curves_.size(); ++i) script_ << (i ? separator : "") << curves_[i];
  script_ << "\n";
  curves_.clear();
}

void GnuplotFigure::PlotArea(const ScreenCoordinates& screen, double left_px, double right_px,
                             double top_px, double bottom_px) {
  script_ << "set lmargin at screen " << screen.X(left_px) << "\n"
          << "set rmargin at screen " << screen.X(right_px) << "\n"
          << "set tmargin at screen " << screen.Y(top_px) << "\n"
          << "set bmargin at screen " << screen.Y(bottom_px) << "\n";
}

std::string GnuplotFigure::Draw(const GnuplotImage& image) const {
  return RunGnuplot(script_.str(), image);
}

}  // namespace uavsim::results
