#include "sensors/image_io.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>

namespace uavsim::sensors {

std::vector<std::uint8_t> EncodePng(const GrayImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height)
    throw std::invalid_argument("EncodePng: image of " + std::to_string(image.width) + " x " +
                                std::to_string(image.height) + " px has " +
                                std::to_string(image.pixels.size()) + " bytes");
  // cv::Mat only wraps the pixels (no copy); imencode does not write to them.
  const cv::Mat view(image.height, image.width, CV_8UC1,
                     const_cast<std::uint8_t*>(image.pixels.data()));
  std::vector<std::uint8_t> png;
  // Level 1: recording 60 images a second matters more than a few % of size.
  if (!cv::imencode(".png", view, png, {cv::IMWRITE_PNG_COMPRESSION, 1}))
    throw std::runtime_error("EncodePng: OpenCV could not encode the image");
  return png;
}

}  // namespace uavsim::sensors
