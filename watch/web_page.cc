#include "watch/web_page.h"

#include "watch/watch_page_html.h"  // generated into the build tree from watch/web/index.html

namespace clogscope::watch {

std::string_view WatchPageHtml() { return {kWatchPageHtml, sizeof kWatchPageHtml - 1}; }

}  // namespace clogscope::watch
