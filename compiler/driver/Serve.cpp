#include "driver/Serve.h"

#include <httplib.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include <nlohmann/json.hpp>

#include "scene/Compile.h"
#include "scene/Page.h"
#include "source/Source.h"

namespace iqc {

namespace fs = std::filesystem;

namespace {

struct Build {
    std::string page;
    std::map<std::string, fs::file_time_type> files;  // what the compile read, with its time
    bool ok = false;
};

fs::file_time_type mtime(const std::string& path) {
    std::error_code ec;
    auto t = fs::last_write_time(path, ec);
    return ec ? fs::file_time_type::min() : t;
}

std::string live_reload_script(unsigned version, double poll_seconds) {
    // Polls /version; a different number means a new build: reload (sliders live in sessionStorage).
    return "const iqcVersion = " + std::to_string(version) +
           ";\n  setInterval(() => fetch('/version', { cache: 'no-store' }).then(r => r.text()).then(v => {\n"
           "    if (Number(v) !== iqcVersion) location.reload();\n  }).catch(() => {}), " +
           std::to_string(static_cast<int>(poll_seconds * 1000)) + ");";
}

Build build(const std::string& input, unsigned version, double poll_seconds) {
    Build b;
    SourceManager sm;
    Diagnostics diags(sm);
    CompileOptions opts;
    opts.target = Target::WebGL2;
    CompileResult r = compile_file(input, sm, diags, opts);
    // Watch every real file the compile read (modules beside the scene, includes), and the input itself.
    b.files[input] = mtime(input);
    for (size_t f = 0; f < sm.size(); ++f) {
        std::string name = sm.name(static_cast<FileId>(f));
        std::error_code ec;
        if (fs::is_regular_file(name, ec)) b.files[name] = mtime(name);
    }
    std::string live = live_reload_script(version, poll_seconds);
    if (r.exit_code == 0) {
        b.page = html_page(r.code, r.meta, live);
        b.ok = true;
    } else {
        std::string text = diags.render();
        if (r.exit_code == 3) text += r.internal;
        nlohmann::json meta = {{"title", fs::path(input).filename().string()}, {"error", text}};
        b.page = html_page("", meta.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), live);
    }
    return b;
}

}  // namespace

int serve(const std::string& input, int port, double poll_seconds) {
    std::error_code ec;
    if (!fs::is_regular_file(input, ec)) {
        std::fprintf(stderr, "iqc: error: cannot read '%s'\n", input.c_str());
        return 1;
    }
    std::mutex mu;
    std::atomic<unsigned> version{1};
    Build current = build(input, version, poll_seconds);
    if (!current.ok) std::fprintf(stderr, "iqc: %s has errors (shown in the page)\n", input.c_str());

    httplib::Server server;
    server.Get("/", [&](const httplib::Request&, httplib::Response& res) {
        std::lock_guard<std::mutex> lock(mu);
        res.set_header("Cache-Control", "no-store");
        res.set_content(current.page, "text/html; charset=utf-8");
    });
    server.Get("/version", [&](const httplib::Request&, httplib::Response& res) {
        res.set_header("Cache-Control", "no-store");
        res.set_content(std::to_string(version.load()), "text/plain");
    });
    // Loopback only: the page is for the person at this machine.
    const char* host = "127.0.0.1";
    int bound = port == 0 ? server.bind_to_any_port(host) : (server.bind_to_port(host, port) ? port : -1);
    if (bound < 0) {
        std::fprintf(stderr, "iqc: error: cannot listen on %s:%d\n", host, port);
        return 1;
    }
    std::printf("iqc: serving %s at http://%s:%d/ (Ctrl-C stops)\n", input.c_str(), host, bound);
    std::fflush(stdout);

    std::atomic<bool> running{true};
    std::thread watcher([&] {
        while (running) {
            std::this_thread::sleep_for(std::chrono::duration<double>(poll_seconds));
            bool changed = false;
            {
                std::lock_guard<std::mutex> lock(mu);
                for (const auto& [path, t] : current.files)
                    if (mtime(path) != t) changed = true;
            }
            if (!changed) continue;
            auto t0 = std::chrono::steady_clock::now();
            Build next = build(input, version + 1, poll_seconds);
            {
                std::lock_guard<std::mutex> lock(mu);
                current = std::move(next);
                ++version;
            }
            double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            std::fprintf(stderr, "iqc: rebuilt (version %u, %s, %.1f ms)\n", version.load(),
                         current.ok ? "ok" : "errors shown in the page", ms);
        }
    });
    server.listen_after_bind();
    running = false;
    watcher.join();
    return 0;
}

}  // namespace iqc
