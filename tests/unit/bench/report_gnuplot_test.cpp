#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "bench/report/gnuplot.hpp"
#include "bench/report/html_parts.hpp"

namespace calbench::report {
namespace {

TEST(ReportGnuplot, Base64KnownVectors) {
  EXPECT_EQ(base64(""), "");
  EXPECT_EQ(base64("f"), "Zg==");
  EXPECT_EQ(base64("fo"), "Zm8=");
  EXPECT_EQ(base64("foo"), "Zm9v");
  EXPECT_EQ(base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64(std::string("\xff\x00\x10", 3)), "/wAQ");
}

TEST(ReportGnuplot, HtmlEscape) {
  EXPECT_EQ(html_escape("<a href=\"x\">O'Brien & co</a>"), "&lt;a href=&quot;x&quot;&gt;O&#39;Brien &amp; co&lt;/a&gt;");
}

TEST(ReportGnuplot, MakesAPngAndReportsScriptErrors) {
  const std::string png = run_gnuplot(
      "set terminal pngcairo size 200,100\nset output 'plot.png'\nplot 'd.dat' using 1:2 with lines\n",
      {{"d.dat", "0 0\n1 1\n2 4\n"}});
  ASSERT_GT(png.size(), 100u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_THROW(run_gnuplot("set output 'plot.png'\nthis is not gnuplot\n", {}), std::runtime_error);
}

TEST(ReportGnuplot, ReadsBackTheNamedOutputOrNone) {
  // An SVG read back by name (the bench diagnosis embeds it inline).
  const std::string svg = run_gnuplot("set terminal svg size 200,100\nset output 'plot.svg'\nplot 'd.dat' using 1:2 with lines\n",
                                      {{"d.dat", "0 0\n1 1\n"}}, "plot.svg");
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  // No output read back: the script writes where it says (identify's PNGs at absolute paths).
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / ("calbench-gnuplot-test-" + std::to_string(::getpid()) + ".png");
  const std::string none = run_gnuplot("set terminal pngcairo size 200,100\nset output '" + out.string() +
                                           "'\nplot 'd.dat' using 1:2 with lines\n",
                                       {{"d.dat", "0 0\n1 1\n"}}, "");
  EXPECT_TRUE(none.empty());
  ASSERT_TRUE(std::filesystem::exists(out));
  EXPECT_GT(std::filesystem::file_size(out), 100u);
  std::filesystem::remove(out);
  // A named output the script did not write is an error.
  EXPECT_THROW(run_gnuplot("set terminal svg\nset output 'other.svg'\nplot x\n", {}, "plot.svg"), std::runtime_error);
}

TEST(ReportGnuplot, PageStartEscapesTheTitle) {
  const std::string h = html_page_start("a <b> & 'c'", "body{margin:0}");
  EXPECT_EQ(h.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(h.find("<title>a &lt;b&gt; &amp; &#39;c&#39;</title>"), std::string::npos);
  EXPECT_NE(h.find("<style>body{margin:0}</style></head><body>"), std::string::npos);
}

}  // namespace
}  // namespace calbench::report
