#include "http/http_target.hpp"

namespace leakmon::http {
namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool is_control(unsigned char c) { return c < 0x20 || c == 0x7f; }

}  // namespace

std::optional<std::string> percent_decode(std::string_view text, bool plus_is_space) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '%') {
      if (i + 2 >= text.size()) return std::nullopt;
      const int high = hex_value(text[i + 1]);
      const int low = hex_value(text[i + 2]);
      if (high < 0 || low < 0) return std::nullopt;
      c = static_cast<unsigned char>(high * 16 + low);
      i += 2;
    } else if (c == '+' && plus_is_space) {
      c = ' ';
    }
    if (is_control(c)) return std::nullopt;
    out += static_cast<char>(c);
  }
  return out;
}

RequestTargetResult parse_request_target(std::string_view target) {
  RequestTargetResult result;
  if (target.empty() || target.front() != '/') {
    result.error = "the request target must start with '/'";
    return result;
  }
  if (target.find('#') != std::string_view::npos) {
    result.error = "a request target has no fragment ('#')";
    return result;
  }
  const std::size_t question = target.find('?');
  const std::string_view raw_path = target.substr(0, question);
  const std::string_view raw_query =
      question == std::string_view::npos ? std::string_view{} : target.substr(question + 1);
  RequestTarget parsed;
  auto path = percent_decode(raw_path, false);
  if (!path) {
    result.error = "malformed percent-escape or control character in the path";
    return result;
  }
  parsed.path = std::move(*path);
  parsed.query = std::string(raw_query);
  std::string_view rest = raw_query;
  while (!rest.empty()) {
    const std::size_t amp = rest.find('&');
    const std::string_view piece = rest.substr(0, amp);
    rest = amp == std::string_view::npos ? std::string_view{} : rest.substr(amp + 1);
    if (piece.empty()) continue;
    const std::size_t equals = piece.find('=');
    QueryParam param;
    param.has_value = equals != std::string_view::npos;
    auto name = percent_decode(piece.substr(0, equals), true);
    auto value = param.has_value ? percent_decode(piece.substr(equals + 1), true)
                                 : std::optional<std::string>(std::string());
    if (!name || !value) {
      result.error = "malformed percent-escape or control character in the query";
      return result;
    }
    param.name = std::move(*name);
    param.value = std::move(*value);
    parsed.params.push_back(std::move(param));
  }
  result.target = std::move(parsed);
  return result;
}

const QueryParam* find_param(std::span<const QueryParam> params, std::string_view name) {
  for (const auto& param : params) {
    if (param.name == name) return &param;
  }
  return nullptr;
}

}  // namespace leakmon::http
