#include "bench/report/gnuplot.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace calbench::report {
namespace fs = std::filesystem;

std::string run_gnuplot(const std::string& script, const std::map<std::string, std::string>& files,
                        const std::string& output) {
  char tmpl[] = "/tmp/calbench_plot_XXXXXX";
  if (!::mkdtemp(tmpl)) throw std::runtime_error("cannot create a temporary folder for gnuplot");
  const fs::path dir = tmpl;
  struct Cleanup {
    fs::path d;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(d, ec);
    }
  } cleanup{dir};
  for (const auto& [name, content] : files) std::ofstream(dir / name, std::ios::binary) << content;
  std::ofstream(dir / "plot.gp", std::ios::binary) << script;
  const fs::path err = dir / "stderr.txt";
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("cannot start gnuplot (fork failed)");
  if (pid == 0) {
    if (::chdir(dir.c_str()) != 0) ::_exit(126);
    const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, 2);
      ::dup2(fd, 1);
    }
    ::execlp("gnuplot", "gnuplot", "plot.gp", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
  }
  std::stringstream msg;
  msg << std::ifstream(err).rdbuf();
  if (!WIFEXITED(status) || WEXITSTATUS(status) == 127)
    throw std::runtime_error("gnuplot not found or crashed (install gnuplot-nox): " + msg.str());
  if (WEXITSTATUS(status) != 0) throw std::runtime_error("gnuplot failed: " + msg.str());
  if (output.empty()) return {};
  std::ifstream out(dir / output, std::ios::binary);
  std::stringstream bytes;
  bytes << out.rdbuf();
  if (bytes.str().size() < 8) throw std::runtime_error("gnuplot failed: " + msg.str());
  return bytes.str();
}

std::string base64(const std::string& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const unsigned v = static_cast<unsigned char>(in[i]) << 16 | static_cast<unsigned char>(in[i + 1]) << 8 |
                       static_cast<unsigned char>(in[i + 2]);
    out += t[v >> 18 & 63];
    out += t[v >> 12 & 63];
    out += t[v >> 6 & 63];
    out += t[v & 63];
  }
  if (i + 1 == in.size()) {
    const unsigned v = static_cast<unsigned char>(in[i]) << 16;
    out += t[v >> 18 & 63];
    out += t[v >> 12 & 63];
    out += "==";
  } else if (i + 2 == in.size()) {
    const unsigned v = static_cast<unsigned char>(in[i]) << 16 | static_cast<unsigned char>(in[i + 1]) << 8;
    out += t[v >> 18 & 63];
    out += t[v >> 12 & 63];
    out += t[v >> 6 & 63];
    out += '=';
  }
  return out;
}

std::string png_data_uri(const std::string& png) { return "data:image/png;base64," + base64(png); }

}  // namespace calbench::report
