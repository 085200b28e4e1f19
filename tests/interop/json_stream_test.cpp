// JsonStream (interop/src/json_stream.h), the writer behind motion.json, against an independent
// reader (nlohmann::json's parser): the nesting and commas it writes parse to the structure
// written, every double reads back to the same bits (random bit patterns across the whole
// exponent range, integral values, signed zeros, subnormals), a non-finite number is null, and
// strings with quotes, backslashes, control characters and UTF-8 survive.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "../../interop/src/json_stream.h"

namespace spacetime {
namespace {

TEST(JsonStream, DoublesReadBackToTheSameBits) {
  std::mt19937_64 rng(5);
  std::vector<double> values{0.0, -0.0, 1.0, -3.0, 0.1, 1e-5, 123456789.0, 1e21, 5e-324,
                             std::numeric_limits<double>::max(), std::numeric_limits<double>::min(),
                             std::numeric_limits<double>::denorm_min() * 12345};
  while (values.size() < 20000) {
    const double v = std::bit_cast<double>(rng());
    if (std::isfinite(v)) values.push_back(v);
  }
  std::string text;
  JsonStream out(&text);
  out.beginArray();
  for (double v : values) out.value(v);
  out.endArray();
  const nlohmann::json read = nlohmann::json::parse(text);
  ASSERT_EQ(read.size(), values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    ASSERT_TRUE(read[i].is_number_float()) << text.substr(0, 200);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(read[i].get<double>()), std::bit_cast<std::uint64_t>(values[i]))
        << "value " << i << ": " << values[i];
  }
  EXPECT_NE(text.find("123456789.0"), std::string::npos);  // integral values stay numbers with a point
}

TEST(JsonStream, WritesTheStructureItWasGiven) {
  std::string text;
  JsonStream out(&text);
  out.beginObject();
  out.key("name");
  out.value("a \"quoted\" \\ name\twith\ncontrol \x01 and UTF-8 \xc3\xa9");
  out.key("empty");
  out.beginArray();
  out.endArray();
  out.key("rows");
  out.beginArray();
  out.array(Eigen::Vector3d(1, 2.5, -0.25));
  out.array(Eigen::Vector2d(std::nan(""), std::numeric_limits<double>::infinity()));
  out.endArray();
  out.key("flags");
  out.beginArray();
  out.value(true);
  out.value(false);
  out.endArray();
  out.key("count");
  out.value(7);
  out.key("nested");
  out.beginObject();
  out.key("x");
  out.value(0.5);
  out.endObject();
  out.endObject();
  const nlohmann::json read = nlohmann::json::parse(text);
  EXPECT_EQ(read["name"], "a \"quoted\" \\ name\twith\ncontrol \x01 and UTF-8 \xc3\xa9");
  EXPECT_TRUE(read["empty"].is_array() && read["empty"].empty());
  EXPECT_EQ(read["rows"][0], nlohmann::json({1.0, 2.5, -0.25}));
  EXPECT_TRUE(read["rows"][1][0].is_null());  // not finite: null, as nlohmann writes it
  EXPECT_TRUE(read["rows"][1][1].is_null());
  EXPECT_EQ(read["flags"], nlohmann::json({true, false}));
  EXPECT_TRUE(read["count"].is_number_integer());
  EXPECT_EQ(read["count"], 7);
  EXPECT_EQ(read["nested"]["x"], 0.5);
  EXPECT_EQ(text.find(' ', text.find("\"count\"")), std::string::npos);  // compact past the strings
}

}  // namespace
}  // namespace spacetime
