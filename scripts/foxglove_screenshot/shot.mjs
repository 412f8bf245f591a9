// Serves Foxglove Studio's web build (index.html, boot.js, studio-base's assets, React) on 127.0.0.1, opens it in
// headless Chromium (Debian's /usr/bin/chromium, driven by playwright-core) connected to a Foxglove WebSocket
// server, waits, and captures the 3-D panel.
//
// Usage: node shot.mjs ws://127.0.0.1:8765 OUT.png [--wait SECONDS] [--size WxH] [--log FILE]
//        node shot.mjs FILE.mcap OUT.png --time RFC3339 [...]   (the file, served over HTTP with ranges, as Foxglove's
//                                                               "remote file" source, seeked to that time)
import { createReadStream, existsSync, realpathSync, statSync, writeFileSync } from "node:fs";
import { createServer } from "node:http";
import { basename, dirname, extname, join, normalize } from "node:path";
import { fileURLToPath } from "node:url";
import { mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { chromium } from "playwright-core";

const here = dirname(fileURLToPath(import.meta.url));
const [source, outPath, ...rest] = process.argv.slice(2);
const live = source.startsWith("ws://");
const opt = (name, fallback) => (rest.includes(name) ? rest[rest.indexOf(name) + 1] : fallback);
const waitSeconds = Number(opt("--wait", "20"));
const [width, height] = opt("--size", "1280x800").split("x").map(Number);
const logPath = opt("--log", undefined);

const roots = {
  "/studio/": join(here, "node_modules/@foxglove/studio-base/assets"),
  "/react/": join(here, "node_modules/react"),
  "/react-dom/": join(here, "node_modules/react-dom"),
  "/": here,
};
if (!live) roots["/data/"] = dirname(realpathSync(source));
const types = { ".html": "text/html", ".js": "application/javascript", ".wasm": "application/wasm", ".png": "image/png",
  ".svg": "image/svg+xml", ".css": "text/css", ".woff2": "font/woff2", ".woff": "font/woff", ".ttf": "font/ttf" };
const server = createServer((req, res) => {
  const path = decodeURIComponent(new URL(req.url, "http://x").pathname);
  const prefix = Object.keys(roots).sort((a, b) => b.length - a.length).find((p) => path.startsWith(p));
  const file = normalize(join(roots[prefix], path.slice(prefix.length) || "index.html"));
  if (!file.startsWith(roots[prefix]) || !existsSync(file) || !statSync(file).isFile()) {
    res.writeHead(404).end();
    return;
  }
  const size = statSync(file).size;
  const headers = { "content-type": types[extname(file)] ?? "application/octet-stream", "accept-ranges": "bytes" };
  const range = /^bytes=(\d+)-(\d*)$/.exec(req.headers.range ?? "");
  if (range) {  // the remote-file reader reads the MCAP file by ranges
    const start = Number(range[1]), end = range[2] ? Math.min(Number(range[2]), size - 1) : size - 1;
    res.writeHead(206, { ...headers, "content-range": `bytes ${start}-${end}/${size}`, "content-length": end - start + 1 });
    if (req.method === "HEAD") res.end();
    else createReadStream(file, { start, end }).pipe(res);
    return;
  }
  res.writeHead(200, { ...headers, "content-length": size });
  if (req.method === "HEAD") res.end();
  else createReadStream(file).pipe(res);
});
await new Promise((ok) => server.listen(0, "127.0.0.1", ok));
const base = `http://127.0.0.1:${server.address().port}`;
const page_url = live
  ? `${base}/index.html?ds=foxglove-websocket&ds.url=${encodeURIComponent(source)}&layoutId=sextant`
  : `${base}/index.html?ds=remote-file&ds.url=${encodeURIComponent(`${base}/data/${basename(source)}`)}` +
    `&time=${encodeURIComponent(opt("--time", ""))}&layoutId=sextant`;

const profile = mkdtempSync(join(tmpdir(), "sextant-chromium-"));  // a fresh profile
const browser = await chromium.launchPersistentContext(profile, {
  executablePath: "/usr/bin/chromium",
  viewport: { width, height },
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync", "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader"],
});
const log = [];
const page = browser.pages()[0] ?? (await browser.newPage());
page.on("console", (m) => log.push(`console.${m.type()}: ${m.text()}`));
page.on("pageerror", (e) => log.push(`pageerror: ${e.message}`));
page.on("requestfailed", (r) => log.push(`requestfailed: ${r.url()} ${r.failure()?.errorText}`));
await page.goto(page_url);
await page.addStyleTag({ content: ".MuiTooltip-popper { display: none !important; }" });  // the onboarding tip
await page.waitForTimeout(waitSeconds * 1000);
// The 3-D panel: the largest canvas on the page.
const clip = await page.evaluate(() => {
  const rects = [...document.querySelectorAll("canvas")].map((c) => c.getBoundingClientRect());
  const r = rects.sort((a, b) => b.width * b.height - a.width * a.height)[0];
  return r && { x: r.x, y: r.y, width: r.width, height: r.height };
});
if (!clip || clip.width < 100) throw new Error("no 3-D panel on the page");
await page.screenshot({ path: outPath, clip });
if (logPath) writeFileSync(logPath, log.join("\n") + "\n");
await browser.close();
server.close();
rmSync(profile, { recursive: true, force: true });
console.log(`shot: ${outPath} (${log.filter((l) => l.startsWith("pageerror")).length} page errors)`);
