#include "scanstop_common/options.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <sstream>

#include "scanstop_common/error.h"

namespace scanstop {
namespace {

std::string shown(const std::string& text) {
  return text.empty() ? "''" : text.size() > 60 ? text.substr(0, 60) + "..." : text;
}

std::string num(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

}  // namespace

long long parseIntegerArg(const std::string& what, const std::string& text, long long min, long long max) {
  const auto fail = [&]() -> long long {
    throw ConfigError(what + " " + shown(text) + ": not an integer in [" + std::to_string(min) + ", " +
                      std::to_string(max) + "]");
  };
  // Digits only after an optional sign: no leading spaces, hex, exponents or trailing characters.
  const size_t start = !text.empty() && (text[0] == '-' || text[0] == '+') ? 1 : 0;
  if (text.size() == start || text.find_first_not_of("0123456789", start) != std::string::npos) return fail();
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (errno == ERANGE || *end != '\0' || v < min || v > max) return fail();
  return v;
}

double parseRealArg(const std::string& what, const std::string& text, double min, double max) {
  const auto fail = [&]() -> double {
    throw ConfigError(what + " " + shown(text) + ": not a number in [" + num(min) + ", " + num(max) + "]");
  };
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return fail();
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(v) || v < min || v > max) return fail();
  return v;
}

std::vector<double> parseRealListArg(const std::string& what, const std::string& text, size_t count, double min,
                                     double max, const std::string& form) {
  std::vector<std::string> items(1);
  for (const char c : text) {
    if (c == ',')
      items.emplace_back();
    else
      items.back() += c;
  }
  if (items.size() != count)
    throw ConfigError(what + " " + shown(text) + ": expected " + form + " (" + std::to_string(count) +
                      " comma-separated numbers), found " + std::to_string(items.size()) + " values");
  std::vector<double> out;
  for (size_t k = 0; k < items.size(); ++k) {
    try {
      out.push_back(parseRealArg(what, items[k], min, max));
    } catch (const ConfigError&) {
      throw ConfigError(what + " " + shown(text) + ": value " + std::to_string(k + 1) + " ('" + shown(items[k]) +
                        "') is not a number in [" + num(min) + ", " + num(max) + "] (expected " + form + ")");
    }
  }
  return out;
}

std::string jsonNumber(double value, int precision) {
  if (!std::isfinite(value)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", precision, value);
  return buf;
}

std::string jsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (u < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", u);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

Options::Options(std::string program, std::string usage) : program_(std::move(program)), usage_(std::move(usage)) {
  if (!usage_.empty() && usage_.back() != '\n') usage_ += '\n';
}

Options& Options::flag(const std::string& name, bool& target, bool value) {
  options_.push_back({name, false, [&target, value](const std::string&) { target = value; }});
  return *this;
}

Options& Options::integer(const std::string& name, int& target, int min, int max) {
  options_.push_back({name, true, [&target, name, min, max](const std::string& v) {
                        target = static_cast<int>(parseIntegerArg(name, v, min, max));
                      }});
  return *this;
}

Options& Options::integer(const std::string& name, long& target, long min, long max) {
  options_.push_back({name, true, [&target, name, min, max](const std::string& v) {
                        target = static_cast<long>(parseIntegerArg(name, v, min, max));
                      }});
  return *this;
}

Options& Options::integer(const std::string& name, size_t& target, size_t min, size_t max) {
  const long long lo = static_cast<long long>(min);
  const long long hi = max > static_cast<size_t>(std::numeric_limits<long long>::max())
                           ? std::numeric_limits<long long>::max()
                           : static_cast<long long>(max);
  options_.push_back({name, true, [&target, name, lo, hi](const std::string& v) {
                        target = static_cast<size_t>(parseIntegerArg(name, v, lo, hi));
                      }});
  return *this;
}

Options& Options::real(const std::string& name, double& target, double min, double max, double scale) {
  options_.push_back({name, true, [&target, name, min, max, scale](const std::string& v) {
                        target = parseRealArg(name, v, min, max) * scale;
                      }});
  return *this;
}

Options& Options::text(const std::string& name, std::string& target) {
  options_.push_back({name, true, [&target](const std::string& v) { target = v; }});
  return *this;
}

Options& Options::choice(const std::string& name, std::string& target, const std::vector<std::string>& allowed) {
  options_.push_back({name, true, [&target, name, allowed](const std::string& v) {
                        for (const std::string& a : allowed)
                          if (v == a) {
                            target = v;
                            return;
                          }
                        std::string list;
                        for (size_t k = 0; k < allowed.size(); ++k) list += (k ? ", " : "") + allowed[k];
                        throw ConfigError(name + " " + shown(v) + ": must be one of " + list);
                      }});
  return *this;
}

Options& Options::custom(const std::string& name, const std::function<void(const std::string&)>& parse) {
  options_.push_back({name, true, parse});
  return *this;
}

Options& Options::positional(const std::string& name, std::string& target, bool required) {
  positionals_.push_back({name, &target, required});
  return *this;
}

Options& Options::rest(const std::string& name, std::vector<std::string>& target) {
  rest_ = &target;
  rest_name_ = name;
  return *this;
}

const Options::Option* Options::find(const std::string& name) const {
  for (const Option& o : options_)
    if (o.name == name) return &o;
  return nullptr;
}

bool Options::parseOrThrow(int argc, const char* const* argv, std::ostream& out) const {
  // --help first: nothing else is looked at (nor created) when it is anywhere on the line.
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      out << usage_;
      return false;
    }
  }
  size_t next_positional = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.size() > 1 && a[0] == '-' &&
        !(a.size() > 1 && (std::isdigit(static_cast<unsigned char>(a[1])) || a[1] == '.'))) {
      const Option* o = find(a);
      if (!o) throw ConfigError("unknown option " + a);
      std::string value;
      if (o->takes_value) {
        if (i + 1 >= argc) throw ConfigError(a + " needs a value");
        value = argv[++i];
        if (value.size() > 1 && value[0] == '-' && value[1] == '-')
          throw ConfigError(a + " needs a value, not " + value);
      }
      o->apply(value);
      continue;
    }
    if (next_positional < positionals_.size()) {
      *positionals_[next_positional++].target = a;
    } else if (rest_) {
      rest_->push_back(a);
    } else {
      throw ConfigError("unexpected argument " + shown(a));
    }
  }
  for (size_t k = next_positional; k < positionals_.size(); ++k)
    if (positionals_[k].required) throw ConfigError(positionals_[k].name + " is required");
  return true;
}

int Options::parse(int argc, const char* const* argv, std::ostream& out, std::ostream& err) const {
  try {
    return parseOrThrow(argc, argv, out) ? -1 : 0;
  } catch (const ConfigError& e) {
    err << program_ << ": " << e.what() << "\n" << usage_;
    return kExitUsage;
  }
}

int Options::parse(int argc, char** argv) const { return parse(argc, argv, std::cout, std::cerr); }

}  // namespace scanstop
