#include "io/logging.hpp"

#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/dist_sink.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>

namespace ts {

namespace {
std::shared_ptr<spdlog::sinks::dist_sink_mt>& dist() {
  static auto d = [] {
    auto s = std::make_shared<spdlog::sinks::dist_sink_mt>();
    auto term = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
    term->set_pattern("[%^%l%$] %v");
    term->set_level(spdlog::level::info);
    s->add_sink(term);
    return s;
  }();
  return d;
}
std::shared_ptr<spdlog::sinks::sink>& file_sink() {
  static std::shared_ptr<spdlog::sinks::sink> f;
  return f;
}
std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt>& held() {
  static std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> h;
  return h;
}
}  // namespace

std::shared_ptr<spdlog::logger> logger(const std::string& module) {
  if (auto l = spdlog::get(module)) return l;
  auto l = std::make_shared<spdlog::logger>(module, dist());
  l->set_level(spdlog::level::debug);
  l->flush_on(spdlog::level::info);  // a failed or killed run keeps its log
  spdlog::register_logger(l);
  return l;
}

void log_to_terminal(bool quiet) {
  auto& sinks = dist()->sinks();
  if (!sinks.empty()) sinks.front()->set_level(quiet ? spdlog::level::warn : spdlog::level::info);
}

void log_hold() {
  if (held()) dist()->remove_sink(held());
  held() = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(4096);
  held()->set_level(spdlog::level::debug);
  dist()->add_sink(held());
}

void log_to_file(const std::filesystem::path& file, bool append) {
  log_close_file();
  auto f = std::make_shared<spdlog::sinks::basic_file_sink_mt>(file.string(), !append);
  f->set_pattern("%Y-%m-%d %H:%M:%S.%e [%n] [%l] %v");
  f->set_level(spdlog::level::debug);
  if (held()) {  // what the set-up logged, first
    for (const auto& m : held()->last_raw()) f->log(m);
    dist()->remove_sink(held());
    held().reset();
  }
  file_sink() = f;
  dist()->add_sink(f);
}

void log_close_file() {
  if (file_sink()) {
    file_sink()->flush();
    dist()->remove_sink(file_sink());
    file_sink().reset();
  }
}

}  // namespace ts
