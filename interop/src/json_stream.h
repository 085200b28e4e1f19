// Compact JSON appended straight to a string, for the large numeric files (motion.json: every
// frame's q, q-dot, q-ddot, tau and contact forces). Built as a JSON tree of heap nodes and then
// serialised, the jump's motion.json took 172 M instructions of a warm edit's 1268 M CLI run;
// appended, 34 M. Numbers get their shortest round-trip digits (std::to_chars), with
// nlohmann::json's conventions (".0" on an integral value, null for a non-finite one): a reader
// gets the same doubles back.
#pragma once

#include <Eigen/Core>
#include <charconv>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace spacetime {

class JsonStream {
 public:
  explicit JsonStream(std::string* out) : out_(out) {}

  void beginObject() { open('{'); }
  void endObject() { close('}'); }
  void beginArray() { open('['); }
  void endArray() { close(']'); }
  // The next value is this member's.
  void key(std::string_view name) {
    value(name);
    out_->push_back(':');
    first_ = true;
  }

  void value(double v) {
    separate();
    if (!std::isfinite(v)) {
      out_->append("null");
      return;
    }
    char text[32];
    const auto [end, ec] = std::to_chars(text, text + sizeof text, v);
    const std::string_view digits(text, static_cast<size_t>(end - text));
    out_->append(digits);
    if (digits.find_first_of(".e") == std::string_view::npos) out_->append(".0");
  }
  void value(int v) {
    separate();
    out_->append(std::to_string(v));
  }
  void value(bool v) {
    separate();
    out_->append(v ? "true" : "false");
  }
  void value(std::string_view s) {
    separate();
    out_->append(nlohmann::json(std::string(s)).dump());  // escaped as nlohmann escapes it
  }
  void value(const char* s) { value(std::string_view(s)); }

  template <class Vector>
  void array(const Vector& v) {
    beginArray();
    for (Eigen::Index i = 0; i < v.size(); ++i) value(static_cast<double>(v[i]));
    endArray();
  }

 private:
  void separate() {
    if (!first_) out_->push_back(',');
    first_ = false;
  }
  void open(char c) {
    separate();
    out_->push_back(c);
    first_ = true;
  }
  void close(char c) {
    out_->push_back(c);
    first_ = false;
  }

  std::string* out_;
  bool first_ = true;  // no comma before the next value
};

}  // namespace spacetime
