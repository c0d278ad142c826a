#include "sim/foxglove_schemas.h"

#include <stdexcept>
#include <utility>
#include <vector>

namespace uavsim::sim {
namespace {

using core::Json;

Json Type(const char* type) { return {{"type", type}}; }
Json NonNegative(const char* type) { return {{"type", type}, {"minimum", 0}}; }
Json ArrayOf(Json items) { return {{"type", "array"}, {"items", std::move(items)}}; }
Json Base64() { return {{"type", "string"}, {"contentEncoding", "base64"}}; }

// An object schema whose every property is required.
Json Object(const std::string& title, std::vector<std::pair<std::string, Json>> properties) {
  Json schema = {{"title", title}, {"type", "object"}};
  Json props = Json::object(), required = Json::array();
  for (auto& [name, value] : properties) {
    required.push_back(name);
    props[name] = std::move(value);
  }
  schema["properties"] = std::move(props);
  schema["required"] = std::move(required);
  return schema;
}

// An enumeration: {"title": ..., "oneOf": [{"title": NAME, "const": i}, ...]}.
Json Enum(const std::string& title, const std::vector<std::string>& names) {
  Json one_of = Json::array();
  for (std::size_t i = 0; i < names.size(); ++i)
    one_of.push_back({{"title", names[i]}, {"const", i}});
  return {{"title", title}, {"oneOf", one_of}};
}

Json Time(const char* title) {
  Json nsec = {{"type", "integer"}, {"minimum", 0}, {"maximum", 999999999}};
  Json sec = std::string(title) == "time" ? NonNegative("integer") : Type("integer");
  return {{"type", "object"}, {"title", title}, {"properties", {{"sec", sec}, {"nsec", nsec}}}};
}

Json Xyz(const std::string& title) {
  return Object(title, {{"x", Type("number")}, {"y", Type("number")}, {"z", Type("number")}});
}
Json Quaternion() {
  return Object(
      "foxglove.Quaternion",
      {{"x", Type("number")}, {"y", Type("number")}, {"z", Type("number")}, {"w", Type("number")}});
}
Json Color() {
  return Object(
      "foxglove.Color",
      {{"r", Type("number")}, {"g", Type("number")}, {"b", Type("number")}, {"a", Type("number")}});
}
Json Pose() {
  return Object("foxglove.Pose",
                {{"position", Xyz("foxglove.Vector3")}, {"orientation", Quaternion()}});
}
Json Indices() { return ArrayOf(NonNegative("integer")); }

// SceneEntity's primitives.
Json Primitives(const std::string& kind) {
  if (kind == "arrows")
    return Object("foxglove.ArrowPrimitive", {{"pose", Pose()},
                                              {"shaft_length", Type("number")},
                                              {"shaft_diameter", Type("number")},
                                              {"head_length", Type("number")},
                                              {"head_diameter", Type("number")},
                                              {"color", Color()}});
  if (kind == "cubes" || kind == "spheres")
    return Object(kind == "cubes" ? "foxglove.CubePrimitive" : "foxglove.SpherePrimitive",
                  {{"pose", Pose()}, {"size", Xyz("foxglove.Vector3")}, {"color", Color()}});
  if (kind == "cylinders")
    return Object("foxglove.CylinderPrimitive", {{"pose", Pose()},
                                                 {"size", Xyz("foxglove.Vector3")},
                                                 {"bottom_scale", Type("number")},
                                                 {"top_scale", Type("number")},
                                                 {"color", Color()}});
  if (kind == "lines")
    return Object("foxglove.LinePrimitive",
                  {{"type", Enum("foxglove.LineType", {"LINE_STRIP", "LINE_LOOP", "LINE_LIST"})},
                   {"pose", Pose()},
                   {"thickness", Type("number")},
                   {"scale_invariant", Type("boolean")},
                   {"points", ArrayOf(Xyz("foxglove.Point3"))},
                   {"color", Color()},
                   {"colors", ArrayOf(Color())},
                   {"indices", Indices()}});
  if (kind == "triangles")
    return Object("foxglove.TriangleListPrimitive", {{"pose", Pose()},
                                                     {"points", ArrayOf(Xyz("foxglove.Point3"))},
                                                     {"color", Color()},
                                                     {"colors", ArrayOf(Color())},
                                                     {"indices", Indices()}});
  if (kind == "texts")
    return Object("foxglove.TextPrimitive", {{"pose", Pose()},
                                             {"billboard", Type("boolean")},
                                             {"font_size", Type("number")},
                                             {"scale_invariant", Type("boolean")},
                                             {"color", Color()},
                                             {"text", Type("string")}});
  return Object("foxglove.ModelPrimitive", {{"pose", Pose()},
                                            {"scale", Xyz("foxglove.Vector3")},
                                            {"color", Color()},
                                            {"override_color", Type("boolean")},
                                            {"url", Type("string")},
                                            {"media_type", Type("string")},
                                            {"data", Base64()}});
}

Json SceneUpdate() {
  std::vector<std::pair<std::string, Json>> entity = {
      {"timestamp", Time("time")},
      {"frame_id", Type("string")},
      {"id", Type("string")},
      {"lifetime", Time("duration")},
      {"frame_locked", Type("boolean")},
      {"metadata", ArrayOf(Object("foxglove.KeyValuePair",
                                  {{"key", Type("string")}, {"value", Type("string")}}))}};
  for (const char* kind :
       {"arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"})
    entity.emplace_back(kind, ArrayOf(Primitives(kind)));
  const Json deletion =
      Object("foxglove.SceneEntityDeletion",
             {{"timestamp", Time("time")},
              {"type", Enum("foxglove.SceneEntityDeletionType", {"MATCHING_ID", "ALL"})},
              {"id", Type("string")}});
  return Object("foxglove.SceneUpdate",
                {{"deletions", ArrayOf(deletion)},
                 {"entities", ArrayOf(Object("foxglove.SceneEntity", std::move(entity)))}});
}

Json PointCloud() {
  const Json numeric = Enum("foxglove.NumericType", {"UNKNOWN", "UINT8", "INT8", "UINT16", "INT16",
                                                     "UINT32", "INT32", "FLOAT32", "FLOAT64"});
  const Json field =
      Object("foxglove.PackedElementField",
             {{"name", Type("string")}, {"offset", NonNegative("integer")}, {"type", numeric}});
  return Object("foxglove.PointCloud", {{"timestamp", Time("time")},
                                        {"frame_id", Type("string")},
                                        {"pose", Pose()},
                                        {"point_stride", NonNegative("integer")},
                                        {"fields", ArrayOf(field)},
                                        {"data", Base64()}});
}

Json CameraCalibration() {
  const auto matrix = [](int n) {
    return Json{{"type", "array"}, {"items", Type("number")}, {"minItems", n}, {"maxItems", n}};
  };
  return Object("foxglove.CameraCalibration", {{"timestamp", Time("time")},
                                               {"frame_id", Type("string")},
                                               {"width", NonNegative("integer")},
                                               {"height", NonNegative("integer")},
                                               {"distortion_model", Type("string")},
                                               {"D", ArrayOf(Type("number"))},
                                               {"K", matrix(9)},
                                               {"R", matrix(9)},
                                               {"P", matrix(12)}});
}

Json UplinkMessage() {
  const Json optional_number = {{"type", {"number", "null"}}};
  Json status = {{"type", "string"}, {"enum", {"delivered", "late", "lost", "in_flight"}}};
  return Object("uavsim.UplinkMessage", {{"timestamp", Time("time")},
                                         {"node", Type("string")},
                                         {"modality", Type("string")},
                                         {"sequence", NonNegative("integer")},
                                         {"bytes", NonNegative("integer")},
                                         {"window", NonNegative("integer")},
                                         {"status", status},
                                         {"t_capture_s", Type("number")},
                                         {"t_arrival_s", optional_number},
                                         {"latency_s", optional_number}});
}

Json WindowError() {
  return Object("uavsim.WindowError",
                {{"timestamp", Time("time")},
                 {"truth", Xyz("foxglove.Vector3")},
                 {"error_m", {{"type", "object"}, {"additionalProperties", Type("number")}}}});
}

}  // namespace

core::Json FoxgloveSchema(const std::string& name) {
  if (name == "foxglove.SceneUpdate") return SceneUpdate();
  if (name == "foxglove.FrameTransform")
    return Object("foxglove.FrameTransform", {{"timestamp", Time("time")},
                                              {"parent_frame_id", Type("string")},
                                              {"child_frame_id", Type("string")},
                                              {"translation", Xyz("foxglove.Vector3")},
                                              {"rotation", Quaternion()}});
  if (name == "foxglove.CompressedImage")
    return Object("foxglove.CompressedImage", {{"timestamp", Time("time")},
                                               {"frame_id", Type("string")},
                                               {"data", Base64()},
                                               {"format", Type("string")}});
  if (name == "foxglove.CameraCalibration") return CameraCalibration();
  if (name == "foxglove.PointCloud") return PointCloud();
  if (name == "uavsim.UplinkMessage") return UplinkMessage();
  if (name == "uavsim.WindowError") return WindowError();
  throw std::invalid_argument("no JSON schema for " + name);
}

}  // namespace uavsim::sim
