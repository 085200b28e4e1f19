// Recursive-descent parser for the formula language (grammar in formula.h).
#include "core/expr/formula.h"

#include <cctype>
#include <cstdio>
#include <cstdlib>

namespace spacetime::expr {
namespace {

struct ParseError {
  size_t position;
  std::string message;
};

// The character that starts at byte `at`, whole: a UTF-8 sequence as it is (a message must stay
// valid UTF-8, and "×" is three bytes), a byte that starts none as \xNN.
std::string characterAt(const std::string& s, size_t at) {
  const auto byte = [&](size_t i) { return static_cast<unsigned char>(s[i]); };
  const unsigned char lead = byte(at);
  const size_t length = lead < 0x80 ? 1 : (lead >> 5) == 0x6 ? 2 : (lead >> 4) == 0xE ? 3 : (lead >> 3) == 0x1E ? 4 : 0;
  bool whole = length > 0 && at + length <= s.size();
  for (size_t i = 1; whole && i < length; ++i) whole = (byte(at + i) >> 6) == 0x2;
  if (whole) return s.substr(at, length);
  char hex[8];
  std::snprintf(hex, sizeof hex, "\\x%02X", lead);
  return hex;
}

// Columns count characters, not bytes: the column of byte `at` of UTF-8 text.
int columnOf(const std::string& s, size_t at) {
  int column = 1;
  for (size_t i = 0; i < at && i < s.size(); ++i)
    if ((static_cast<unsigned char>(s[i]) >> 6) != 0x2) ++column;
  return column;
}

class Parser {
 public:
  Parser(const std::string& text, Graph& g, FormulaEnvironment& env) : s_(text), g_(g), env_(env) {}

  Expr parse() {
    FormulaValue v = sum();
    skip();
    if (pos_ < s_.size())
      fail(pos_, "unexpected '" + characterAt(s_, pos_) + "'; expected an operator or the end");
    if (v.isVector) fail(0, "the formula is a vector; pick a component such as .x, .y or .z");
    return v.scalar;
  }

 private:
  [[noreturn]] void fail(size_t at, const std::string& message) { throw ParseError{at, message}; }
  void skip() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool accept(char c) {
    skip();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  void expect(char c, const std::string& what) {
    if (!accept(c)) {
      skip();
      fail(pos_, std::string("expected '") + c + "' " + what +
                     (pos_ < s_.size() ? std::string(", found '") + s_[pos_] + "'" : ", found the end"));
    }
  }
  std::string name() {
    skip();
    const size_t start = pos_;
    while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_')) ++pos_;
    if (start == pos_) fail(pos_, "expected a name");
    return s_.substr(start, pos_ - start);
  }
  static FormulaValue scalar(Expr e) { return {false, e, {}}; }
  Expr needScalar(const FormulaValue& v, size_t at) {
    if (v.isVector) fail(at, "a vector cannot be used here; pick a component such as .y");
    return v.scalar;
  }

  FormulaValue sum() {
    size_t at = (skip(), pos_);
    FormulaValue v = product();
    for (;;) {
      if (accept('+')) {
        const size_t r = (skip(), pos_);
        v = scalar(needScalar(v, at) + needScalar(product(), r));
      } else if (accept('-')) {
        const size_t r = (skip(), pos_);
        v = scalar(needScalar(v, at) - needScalar(product(), r));
      } else {
        return v;
      }
    }
  }
  FormulaValue product() {
    size_t at = (skip(), pos_);
    FormulaValue v = unary();
    for (;;) {
      if (accept('*')) {
        const size_t r = (skip(), pos_);
        v = scalar(needScalar(v, at) * needScalar(unary(), r));
      } else if (accept('/')) {
        const size_t r = (skip(), pos_);
        v = scalar(needScalar(v, at) / needScalar(unary(), r));
      } else {
        return v;
      }
    }
  }
  FormulaValue unary() {
    if (accept('-')) {
      const size_t at = (skip(), pos_);
      return scalar(-needScalar(unary(), at));
    }
    return power();
  }
  FormulaValue power() {
    const size_t at = (skip(), pos_);
    FormulaValue base = postfix();
    if (accept('^')) {
      const size_t r = (skip(), pos_);
      return scalar(pow(needScalar(base, at), needScalar(unary(), r)));
    }
    return base;
  }
  FormulaValue postfix() {
    FormulaValue v = primary();
    while (accept('.')) {
      const size_t at = (skip(), pos_);
      const std::string c = name();
      if (!v.isVector) fail(at, "'." + c + "' needs a vector before it, such as pos(head)");
      if (c != "x" && c != "y" && c != "z") fail(at, "unknown component '" + c + "'; expected x, y or z");
      v = scalar(v.vector[c[0] - 'x']);
    }
    return v;
  }
  double number() {
    skip();
    const char* begin = s_.c_str() + pos_;
    char* end = nullptr;
    const double d = std::strtod(begin, &end);
    if (end == begin) fail(pos_, "expected a number");
    pos_ += static_cast<size_t>(end - begin);
    return d;
  }
  FormulaValue primary() {
    skip();
    if (pos_ >= s_.size()) fail(pos_, "expected a number, a name or '(' but the formula ended");
    const char c = s_[pos_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return scalar(g_.constant(number()));
    if (accept('(')) {
      FormulaValue v = sum();
      expect(')', "to close '('");
      return v;
    }
    if (accept('[')) {
      FormulaValue v;
      v.isVector = true;
      for (int k = 0; k < 3; ++k) {
        const size_t at = (skip(), pos_);
        v.vector[k] = needScalar(sum(), at);
        if (k < 2) expect(',', "between vector components");
      }
      expect(']', "to close the vector");
      return v;
    }
    if (!std::isalpha(static_cast<unsigned char>(c)) && c != '_')
      fail(pos_, "unexpected '" + characterAt(s_, pos_) + "'; expected a number, a name or '('");
    const size_t at = pos_;
    const std::string n = name();
    if (accept('(')) return call(n, at);
    if (env_.isGroup(n)) {
      expect('.', "after '" + n + "' (such as " + n + ".elbow)");
      const size_t mat = (skip(), pos_);
      const std::string m = name();
      std::string error;
      const std::optional<Expr> e = env_.member(n, m, &error);
      if (!e) fail(mat, error);
      return scalar(*e);
    }
    std::string error;
    const std::optional<FormulaValue> v = env_.name(n, &error);
    if (!v) fail(at, error);
    return *v;
  }
  FormulaValue call(const std::string& fn, size_t at) {
    static const char* unaryNames[] = {"sin", "cos", "tan", "exp", "log", "sqrt", "abs"};
    for (const char* u : unaryNames)
      if (fn == u) {
        const size_t a = (skip(), pos_);
        const Expr x = needScalar(sum(), a);
        expect(')', "after the argument of '" + fn + "'");
        const Op op = fn == "sin" ? Op::Sin : fn == "cos" ? Op::Cos : fn == "tan" ? Op::Tan
                      : fn == "exp" ? Op::Exp : fn == "log" ? Op::Log : fn == "sqrt" ? Op::Sqrt : Op::Abs;
        return scalar(x.graph ? g_.make(op, x) : g_.make(op, g_.constant(x.constant)));
      }
    if (fn == "pow" || fn == "min" || fn == "max") {
      const size_t a = (skip(), pos_);
      const Expr x = needScalar(sum(), a);
      expect(',', "between the two arguments of '" + fn + "'");
      const size_t b = (skip(), pos_);
      const Expr y = needScalar(sum(), b);
      expect(')', "after the arguments of '" + fn + "'");
      return scalar(fn == "pow" ? pow(x, y) : fn == "min" ? min(x, y) : max(x, y));
    }
    if (env_.isBodyFunction(fn)) {
      const size_t bodyAt = (skip(), pos_);
      const std::string body = name();
      std::optional<std::array<double, 3>> point;
      if (accept(',')) {
        expect('[', "to start the body point, such as [0.1, 0, 0]");
        std::array<double, 3> p{};
        for (int k = 0; k < 3; ++k) {
          const bool negative = accept('-');
          p[k] = negative ? -number() : number();
          if (k < 2) expect(',', "between the point's coordinates");
        }
        expect(']', "to close the body point");
        point = p;
      }
      expect(')', "after the arguments of '" + fn + "'");
      std::string error;
      const auto v = env_.bodyFunction(fn, body, point, &error);
      if (!v) fail(bodyAt, error);
      FormulaValue out;
      out.isVector = true;
      out.vector = *v;
      return out;
    }
    fail(at, "unknown function '" + fn + "'; expected sin, cos, tan, exp, log, sqrt, abs, pow, min, "
                                          "max, pos, vel or force");
  }

  const std::string& s_;
  Graph& g_;
  FormulaEnvironment& env_;
  size_t pos_ = 0;
};

}  // namespace

FormulaResult parseFormula(const std::string& text, Graph& g, FormulaEnvironment& env) {
  FormulaResult r;
  try {
    Expr e = Parser(text, g, env).parse();
    r.value = e.graph ? e : g.constant(e.constant);
  } catch (const ParseError& e) {
    r.column = columnOf(text, e.position);
    r.error = "column " + std::to_string(r.column) + ": " + e.message;
  }
  return r;
}

}  // namespace spacetime::expr
