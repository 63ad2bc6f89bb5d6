-- test_report.lua: femlod.report (the summary, the HTML page: Table 1 rows,
-- SVG histograms, the embedded GLB, atomic writing, determinism, errors),
-- report.sweep_page, and the `femlod report` command. The page in a browser
-- is tests/report/check.js's business.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"
local report = require "femlod.report"
local sweep = require "femlod.sweep"

local P = params
assert(P and P.femlod and P.tmp and P.shared and P.examples, "run through ctest: needs femlod=, tmp=, shared=, examples=")
local function path(name) return P.tmp .. "/report_" .. name end
local quote = T.quote
local R = T.runner(P.femlod, path("stderr.txt"))
local run = R.run
local function count(s, pat)
  local n = 0
  for _ in s:gmatch(pat) do n = n + 1 end
  return n
end

T.eq(femlod.report, report.report, "femlod.report is femlod.report's report()")

-- {====== base64 (RFC 4648 test vectors)
for _, v in ipairs { { "", "" }, { "f", "Zg==" }, { "fo", "Zm8=" }, { "foo", "Zm9v" }, { "foob", "Zm9vYg==" },
  { "fooba", "Zm9vYmE=" }, { "foobar", "Zm9vYmFy" }, { "\0\255\128", "AP+A" } } do
  T.eq(report.base64(v[1]), v[2], "base64 of " .. T.show(v[1]))
end
-- }======

local input <close> = femlod.load(P.shared .. "/fandisk.obj")
local h <close> = input:simplify { target = 2000, min_stretch = 0.3 }
local mesh <close> = h:mesh()

-- {====== the summary
do
  local r = femlod.report(mesh, { reference = input, name = "fan2k", reference_name = "fandisk.obj" })
  local q = mesh:quality(input)
  T.eq(r.name, "fan2k", "name")
  T.eq(r.quality.triangles, 2000, "quality table")
  T.eq(r.hausdorff, q.hausdorff, "deviation: the Hausdorff distance to the reference")
  T.eq(r.hausdorff_rel, q.hausdorff_rel, "relative deviation")
  T.eq(r.row, report.row(q, "fan2k", "result"), "Table 1 row")
  T.eq(r.reference_row, report.row(input, "fandisk.obj", "reference"), "the reference's row")
  T.eq(r.text, report.text(q, "fan2k"), "text report")
  T.eq(r.html, nil, "no page without html")
  T.eq(r.viewer, false, "no viewer without a page")
  local sum = 0
  for _, n in ipairs(r.histograms.stretch) do sum = sum + n end
  T.eq(sum, 2000, "stretch histogram counts every triangle")
  sum = 0
  for _, n in ipairs(r.histograms.size) do sum = sum + n end
  local edges = r.histograms.size_edges
  T.eq(#r.histograms.size, #edges - 1, "a size bin between two edges")
  T.check(#r.histograms.size >= 5 and #r.histograms.size <= 10, "5 to 10 size bins: " .. #r.histograms.size)
  T.eq(sum, 2000, "size histogram counts every triangle")
  T.eq(r.histograms.size_max, q.size_max, "size bins up to the largest size")
  T.check(edges[#edges] >= q.size_max and edges[#edges - 1] < q.size_max, "the last size bin holds the largest")
  local step = edges[2] - edges[1]
  local mant = step / 10 ^ math.floor(math.log(step, 10) + 1e-9)
  T.check(math.abs(mant - 1) < 1e-9 or math.abs(mant - 2) < 1e-9 or math.abs(mant - 2.5) < 1e-9
    or math.abs(mant - 5) < 1e-9, "size bins of a nice width: " .. step)
  sum = 0
  local vmax = 0
  for _, e in ipairs(r.histograms.valence) do
    sum = sum + e.count
    vmax = math.max(vmax, e.count > 0 and e.valence or 0)
  end
  T.eq(sum, q.vertices, "valence histogram counts every vertex")
  T.eq(vmax, q.valence_max, "largest valence = the report's valence_max")
  -- max_deviation: a measured deviation above what was asked is flagged
  local over = femlod.report(mesh, { reference = input, max_deviation = q.hausdorff / 2 })
  T.eq(over.deviation_exceeded, true, "a deviation above max_deviation is flagged")
  T.check(over.text:find("\n  deviation   EXCEEDS max_deviation ", 1, true), "the text says so: " .. over.text)
  local within = femlod.report(mesh, { reference = input, max_deviation = q.hausdorff * 2 })
  T.eq(within.deviation_exceeded, false, "within max_deviation: not flagged")
  T.check(within.text:find("\n  deviation   within max_deviation ", 1, true), "the text says within")
  T.eq(r.deviation_exceeded, false, "no max_deviation given: nothing to exceed")
  local no_ref = report.report(mesh)
  T.eq(no_ref.hausdorff, nil, "no deviation without a reference")
  T.eq(no_ref.reference_row, nil, "no reference row")
end
-- }======

-- {====== the reference as a path, as `femlod report --reference` takes it
do
  local file = P.shared .. "/fandisk.obj"
  local r = femlod.report(mesh, { reference = file, name = "fan2k" })
  local q = mesh:quality(input)
  T.eq(r.hausdorff, q.hausdorff, "path reference: the deviation from the mesh in the file")
  T.eq(r.hausdorff_rel, q.hausdorff_rel, "path reference: relative deviation")
  T.eq(r.reference_row, report.row(input, "fandisk.obj", "reference"), "path reference: named by its file")
  T.eq(r.row, report.row(q, "fan2k", "result"), "path reference: the result's row")
  r = femlod.report(mesh, { reference = file, reference_name = "input" })
  T.eq(r.reference_row, report.row(input, "input", "reference"), "path reference: reference_name wins")
  local page = path("pathref.html")
  os.remove(page)
  femlod.report(mesh, { reference = file, html = page, viewer = false })
  local s = T.readfile(page) or ""
  T.check(s:find('<td class="name">fandisk%.obj %([^)]*%)</td><td class="name">reference</td><td>12946</td>'),
    "path reference: its row on the page")
  T.check(s:find('<p id="deviation">'), "path reference: the deviation on the page")
  os.remove(page)
  -- femlod.load's errors, at the caller's line
  local missing = path("missing.obj")
  os.remove(missing)
  local line = T.line() + 1
  local ok, msg = pcall(function() femlod.report(mesh, { reference = missing }) end)
  T.eq(ok, false, "a missing reference file raises")
  T.eq(msg and msg:match("[^/]*$"), "report_missing.obj: cannot open: No such file or directory",
    "a missing reference: femlod.load's message")
  T.check(msg and msg:find("^[^:]*test_report%.lua:" .. line .. ": "), "a missing reference: at the caller's line: "
    .. tostring(msg))
  T.checkerr("test_report%.lua:%d+: [^:]*README%.md: unknown file extension", function()
    femlod.report(mesh, { reference = P.examples .. "/../README.md" })
  end)
  -- A recorded run lists the reference among the files read.
  local recipe, rec = path("pathref.lua"), path("pathref.json")
  T.writefile(recipe, "local m <close> = femlod.load(params.mesh)\n"
    .. "print(femlod.report(m, { reference = params.ref }).reference_row)\n")
  local code, out, err = run("--record", rec, "run", recipe, "mesh=" .. P.data .. "/tetra.off", "ref=" .. file)
  T.eq(code, 0, "report with a path reference in a recorded run: " .. err)
  T.check(out:find("^fandisk%.obj %([^)]*%) | reference | 12946 | "), "the reference's row: " .. out)
  T.check((T.readfile(rec) or ""):find('"path":%s*"' .. file:gsub("%p", "%%%0") .. '",%s*"sha256"'),
    "the record lists the reference as read")
end
-- }======

-- {====== pages
local page = path("fan2k.html")
os.remove(page)
do
  local r = femlod.report(mesh, { reference = input, html = page, name = "fan2k", viewer = false })
  T.eq(r.html, page, "page path in the summary")
  T.eq(r.viewer, false, "viewer = false: no 3D view")
  local s = T.readfile(page)
  T.check(s and s:find("^<!DOCTYPE html>\n"), "an HTML page")
  T.check(s:find("</html>\n$"), "complete")
  for _, id in ipairs { "stretch-histogram", "size-histogram", "valence-histogram" } do
    T.check(s:find('<svg id="' .. id .. '"', 1, true), id)
  end
  T.eq(count(s, '<rect class="bar"'), 10 + #r.histograms.size + #r.histograms.valence, "one bar per bin")
  T.check(s:find("<td>2000</td>", 1, true), "Table 1 row in the page")
  T.check(s:find('<p id="deviation">Hausdorff deviation from the reference: <b>' .. report.text(r.quality):match(
    "hausdorff%s+(%S+)"), 1, true), "deviation in the page")
  T.check(not s:find("<model-viewer", 1, true), "no viewer element")
  -- Same mesh, same options: the same bytes.
  femlod.report(mesh, { reference = input, html = page, name = "fan2k", viewer = false })
  T.eq(T.readfile(page), s, "pages are deterministic")
end

-- With the viewer (the build's copy, made by the ctest fixture report_viewer).
local viewer_js
for _, p in ipairs(femlod._VIEWER_PATHS) do
  if not viewer_js and T.exists(p) then viewer_js = p end
end
T.check(viewer_js, "model-viewer.min.js in the build (ctest fixture report_viewer)")
do
  local r = femlod.report(mesh, { html = page, name = "fan2k" })
  T.eq(r.viewer, true, "the 3D view")
  local s = T.readfile(page)
  local b64 = s:match('<model%-viewer id="viewer"[^>]* src="data:model/gltf%-binary;base64,([A-Za-z0-9+/=]+)"')
  T.check(b64, "GLB as a data URI in the viewer element")
  T.eq(b64:sub(1, 8), report.base64("glTF\2\0\0\0"):sub(1, 8), "the data is a GLB, version 2")
  T.check(s:find('<script type="module">', 1, true), "the viewer's module inline")
  local js = T.readfile(viewer_js)
  T.check(#s > #js, "the whole viewer is inlined")
  T.check(not s:find("</script", s:find('<script type="module">', 1, true) + 1, true)
    or s:find("</script", s:find('<script type="module">', 1, true) + 1, true) > #s - 40,
    "no </script inside the inline module")
  T.check(s:find("femlod stretch", 1, true) == nil, "GLB only as base64, not as text")
  local again = femlod.report(mesh, { html = page .. ".2", name = "fan2k", viewer = viewer_js })
  T.eq(T.readfile(page .. ".2"), s, "explicit viewer path: the same page")
  T.eq(again.viewer, true, "viewer by path")
  os.remove(page .. ".2")
end

-- Failures: the old page is kept, no temporary is left behind.
local function leftovers(dir, stem)
  local p = io.popen("ls -a " .. quote(dir))
  local n = 0
  for f in p:lines() do
    if f:find(stem, 1, true) and f:find("%.part$") then n = n + 1 end
  end
  p:close()
  return n
end
do
  local before = T.readfile(page)
  T.checkerr("test_report%.lua:%d+: viewer: cannot read '/nonexistent/mv%.js'", function()
    femlod.report(mesh, { html = page, viewer = "/nonexistent/mv.js" })
  end)
  T.eq(T.readfile(page), before, "failed report: the old page is kept")
  T.checkerr("x%.html: cannot create temporary file: No such file or directory", femlod.report, mesh,
    { html = P.tmp .. "/no/such/dir/x.html", viewer = false })
  T.checkerr("test_report%.lua:%d+: " .. (P.tmp:gsub("%p", "%%%0")) .. ": cannot write: Is a directory",
    function() femlod.report(mesh, { html = P.tmp, viewer = false }) end)
  T.eq(leftovers(P.tmp, "tmp."), 0, "no temporary left in the folder")
  T.eq(leftovers(P.tmp, "report_fan2k"), 0, "no temporary left beside the page")
end
-- }======

-- {====== axes: nice ticks that cover the data
do
  local function same(a, b) return table.concat(a, " ") == table.concat(b, " ") end
  local t, st = report.ticks(0, 1586, 4)
  T.check(same(t, { 0, 500, 1000, 1500, 2000 }), "counts to 1586: " .. table.concat(t, " "))
  T.eq(st, 500, "step 500")
  t = report.ticks(0, 18.1, 10)
  T.check(same(t, { 0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20 }), "sizes to 18.1: " .. table.concat(t, " "))
  t = report.ticks(3, 48, 8)
  T.eq(t[#t], 50, "valence 3..48: the axis reaches 50")
  T.eq(t[1], 0, "and starts at 0")
  t, st = report.ticks(0.2437, 0.7712, 4)
  T.check(same(t, { 0.2, 0.4, 0.6, 0.8 }), "stretch 0.24..0.77: " .. table.concat(t, " "))
  T.eq(report.tick_text(0.30000000000000004, st), "0.3", "labels carry the step's decimals")
  t, st = report.ticks(1500, 3000, 4)
  T.check(same(t, { 1500, 2000, 2500, 3000 }), "elements 1500..3000: " .. table.concat(t, " "))
  t, st = report.ticks(0.001, 0.0046, 4)
  T.eq(report.tick_text(t[#t], st), "0.005", "small values")
  t = report.ticks(5, 5)
  T.check(t[1] < 5 and t[#t] > 5, "one value: an interval around it")
  T.checkerr("finite numbers expected", report.ticks, 0, 1 / 0)
end

-- Every tick of a chart: a nice step, labels equally spaced.
local function chart_ticks(svg, class)
  local vals = {}
  for v in svg:gmatch('class="tick ' .. class .. '"[^>]*>([^<]+)<') do vals[#vals + 1] = tonumber(v) end
  return vals
end
local function nice_axis(vals, what)
  T.check(#vals >= 2, what .. ": ticks")
  local step = vals[2] - vals[1]
  for i = 2, #vals do
    T.check(math.abs(vals[i] - vals[i - 1] - step) < 1e-9 * math.max(1, step), what .. ": equal steps")
  end
  local mant = step / 10 ^ math.floor(math.log(step, 10) + 1e-9)
  T.check(({ [1] = true, [2] = true, [2.5] = true, [5] = true })[tonumber(string.format("%.6g", mant))],
    what .. ": a nice step " .. step)
  for _, v in ipairs(vals) do
    T.check(math.abs(v / step - math.floor(v / step + 0.5)) < 1e-6, what .. ": ticks on multiples of the step " .. v)
  end
end
-- }======

-- {====== the mesh page: rounded ticks, axes to their maxima, the stretch
-- histogram's lowest bins visible, the threshold marked
do
  local pg = path("ticks.html")
  local r = femlod.report(mesh, { html = pg, name = "fan2k", viewer = false, min_stretch = 0.3 })
  local s = T.readfile(pg)
  local q = r.quality
  for _, id in ipairs { "stretch-histogram", "size-histogram", "valence-histogram" } do
    local svg = s:match('<svg id="' .. id:gsub("%p", "%%%0") .. '".-</svg>')
    local x, y = chart_ticks(svg, "xtick"), chart_ticks(svg, "ytick")
    nice_axis(x, id .. " x")
    if id ~= "stretch-histogram" then nice_axis(y, id .. " y") end
    local most = 0
    for c in svg:gmatch("<title>[^<]*: (%d+)</title>") do most = math.max(most, tonumber(c)) end
    T.check(y[#y] >= most, id .. ": the count axis covers the largest bin " .. most .. " (" .. y[#y] .. ")")
  end
  local vsvg = s:match('<svg id="valence%-histogram".-</svg>')
  local vx = chart_ticks(vsvg, "xtick")
  T.check(vx[#vx] >= q.valence_max, "the valence axis covers the largest valence " .. q.valence_max)
  local zx = chart_ticks(s:match('<svg id="size%-histogram".-</svg>'), "xtick")
  T.check(zx[#zx] >= q.size_max, "the size axis covers the largest size")
  -- the stretch histogram: log scale, counts on every bar, the threshold
  local ssvg = s:match('<svg id="stretch%-histogram".-</svg>')
  T.check(ssvg:find("log scale", 1, true), "stretch histogram on a log scale")
  T.eq(count(ssvg, 'class="count"'), 10, "a count over every stretch bar")
  local counted = {}
  for c in ssvg:gmatch('class="count"[^>]*>(%d+)<') do counted[#counted + 1] = tonumber(c) end
  T.eq(table.concat(counted, " "), table.concat(q.histogram, " "), "the counts are the histogram")
  for h, c in ssvg:gmatch('<rect class="bar"[^>]* height="([%d.]+)"><title>[^<]*: (%d+)</title>') do
    if tonumber(c) > 0 then T.check(tonumber(h) >= 2, "a bin of " .. c .. " is a visible bar: " .. h) end
  end
  local mx = ssvg:match('<line id="stretch%-histogram%-mark" x1="([%d.]+)"')
  T.check(mx, "the threshold is marked")
  -- the plot spans x 64..408 for stretch 0..1
  T.check(math.abs(tonumber(mx) - (64 + 344 * 0.3)) < 0.01, "the mark at 0.3: " .. tostring(mx))
  local below = q.histogram[1] + q.histogram[2] + q.histogram[3]
  T.eq(r.below_min_stretch, below, "triangles below the threshold: the bins below 0.3")
  T.check(ssvg:find("min_stretch 0.3: " .. below .. " triangle", 1, true), "the mark says how many are below")
  T.check(s:find('<p id="below-threshold">', 1, true), "and the page says it in words")
  -- default: the simplifier's default; false: no mark
  r = femlod.report(mesh, { html = pg, viewer = false })
  T.eq(r.min_stretch, 0.2, "default threshold: the simplifier's 0.2")
  T.check(T.readfile(pg):find("default min_stretch 0.2", 1, true), "the default is named as such")
  r = femlod.report(mesh, { html = pg, viewer = false, min_stretch = false })
  T.check(not T.readfile(pg):find("histogram-mark", 1, true), "min_stretch = false: no mark")
  T.eq(r.below_min_stretch, nil, "nor a count")
  -- one sliver among good triangles: its bin is a visible bar with its count
  local sl = femlod.mesh { positions = { { 0, 0, 0 }, { 1, 0, 0 }, { 0.5, 0.866, 0 }, { 0.5, -0.01, 0 } },
    triangles = { { 1, 2, 3 }, { 1, 4, 2 } } }
  r = femlod.report(sl, { html = pg, viewer = false })
  s = T.readfile(pg):match('<svg id="stretch%-histogram".-</svg>')
  local h1 = s:match('height="([%d.]+)"><title>stretch %[0%.0, 0%.1%): 1</title>')
  T.check(h1 and tonumber(h1) >= 2, "a single sliver is a visible bar: " .. tostring(h1))
  T.eq(r.below_min_stretch, 1, "one triangle below 0.2")
  -- one valence only: whole-number ticks around it
  local one = femlod.mesh { positions = { { 0, 0, 0 }, { 1, 0, 0 }, { 0.5, 0.8, 0 } }, triangles = { { 1, 2, 3 } } }
  femlod.report(one, { html = pg, viewer = false })
  T.eq(table.concat(chart_ticks(T.readfile(pg):match('<svg id="valence%-histogram".-</svg>'), "xtick"), " "),
    "1 2 3", "a single valence: ticks 1 2 3")
  os.remove(pg)
end
-- }======

-- {====== a large mesh: shown through a copy simplified for display
do
  local pg = path("display.html")
  local r = femlod.report(input, { html = pg, name = "fandisk", display_triangles = 3000 })
  local s = T.readfile(pg)
  T.check(r.display_triangles and r.display_triangles <= 3300, "a display copy near 3000: "
    .. tostring(r.display_triangles))
  T.check(s:find('<p class="note" id="display%-note">The 3D view shows a copy simplified for display with '
    .. 'femlod%.simplify: ' .. r.display_triangles .. " of the mesh&#39;s 12946 triangles"), "the page says so")
  T.check(s:find("<td>12946</td>", 1, true), "the table is the full mesh's")
  local b64 = s:match('src="data:model/gltf%-binary;base64,([A-Za-z0-9+/=]+)"')
  local full = input:encode("f.glb", { color_by = "stretch" })
  T.check(#b64 * 3 / 4 < #full / 4, "the display GLB is a fraction of the full one: " .. #b64 * 3 // 4 .. " < "
    .. #full)
  local whole = femlod.report(input, { html = pg, name = "fandisk" })
  T.eq(whole.display_triangles, nil, "below the default 20,000: the mesh itself")
  T.check(not T.readfile(pg):find("display%-note"), "and no note")
  os.remove(pg)
end
-- }======

-- {====== an empty mesh: a page all the same
do
  local empty = femlod.mesh {}
  local ep = path("empty.html")
  local r = femlod.report(empty, { html = ep, viewer = false })
  T.eq(r.quality.triangles, 0, "no triangles")
  T.eq(#r.histograms.valence, 0, "no valences")
  local s = T.readfile(ep)
  T.check(s and s:find("</html>\n$"), "complete page")
  T.eq(count(s, '<rect class="bar"'), 20, "empty stretch and size bins, no valence bars")
  os.remove(ep)
end
-- }======

-- {====== argument errors
T.checkerr("test_report%.lua:%d+: bad argument #1 to 'report' %(femlod.Mesh expected, got nil%)",
  function() femlod.report() end)
T.checkerr("bad argument #1 to 'report' %(femlod.Mesh expected, got femlod.Hierarchy%)", femlod.report, h)
T.checkerr("test_report%.lua:%d+: bad argument #2 to 'report' %(unknown option 'htm'; valid: "
  .. "display_triangles, html, max_deviation, min_stretch, name, progress, reference, reference_name, title, viewer%)",
  function() femlod.report(mesh, { htm = "x" }) end)
T.checkerr("min_stretch: number in %[0, 1%] or false expected, got 2", femlod.report, mesh, { min_stretch = 2 })
T.checkerr("display_triangles: integer >= 100 or false expected, got 10", femlod.report, mesh,
  { display_triangles = 10 })
T.checkerr("bad argument #2 to 'report' %(max_deviation: positive number expected, got 0%)", femlod.report, mesh,
  { max_deviation = 0 })
T.checkerr("bad argument #2 to 'report' %(table expected, got string%)", femlod.report, mesh, "x.html")
T.checkerr("bad argument #2 to 'report' %(reference: femlod.Mesh or path expected, got table%)", femlod.report,
  mesh, { reference = {} })
T.checkerr("bad argument #2 to 'report' %(reference: femlod.Mesh or path expected, got femlod.Hierarchy%)",
  femlod.report, mesh, { reference = h })
T.checkerr("bad argument #2 to 'report' %(html: string expected, got number%)", femlod.report, mesh, { html = 1 })
T.checkerr("bad argument #2 to 'report' %(viewer: path or false expected, got boolean%)", femlod.report, mesh,
  { viewer = true })
do
  local closed = mesh:copy()
  closed:close()
  T.checkerr("attempt to use a closed femlod.Mesh", femlod.report, closed)
end
-- }======

-- {====== under a sweep's record: the page is logged, the temporary GLB is not
do
  local reg = debug.getregistry()
  local hook = sweep.start({}, {})
  reg["femlod.io_hook"] = hook
  local ok, err = pcall(femlod.report, mesh, { html = page, name = "fan2k" })
  reg["femlod.io_hook"] = nil
  T.check(ok, tostring(err))
  local r = sweep.result()
  T.eq(#r.writes, 1, "one file written: " .. table.concat(r.writes, " "))
  T.eq(r.writes[1], page, "the page")
  T.eq(#r.meshes, 0, "the temporary GLB is not a mesh of the run")
end
-- }======

-- {====== the sweep page
do
  local man = {
    digest = "abc", femlod = "femlod 0.1.0", recipe = { path = "r.lua" },
    grid = { { name = "target", values = { 10, 20 } } },
    points = {
      { index = 0, status = "ok", params = { target = 10 }, error = nil,
        meshes = { { path = "points/000/m.obj", triangles = 10, stretch_avg = 0.8, stretch_min = 0.5, size_max = 1,
          valence_max = 6, hausdorff_rel = 0.01 } } },
      { index = 1, status = "failed", params = { target = 20 }, error = "r.lua:3: <boom>", meshes = {} },
      { index = 2, status = "ok", params = { target = 30 },
        meshes = { { path = "points/002/m.obj", triangles = 30, stretch_avg = 0.7, stretch_min = 0.4, size_max = 2,
          valence_max = 7, hausdorff_rel = 0.002 } } },
    },
  }
  local sp = path("sweep.html")
  T.eq(report.sweep_page(man, sp), sp, "returns the path")
  local s = T.readfile(sp)
  for _, id in ipairs { "sweep-stretch-avg", "sweep-stretch-min", "sweep-deviation" } do
    local svg = s:match('<svg id="' .. id:gsub("%p", "%%%0") .. '".-</svg>')
    T.check(svg, id)
    T.eq(count(svg or "", '<circle class="dot"'), 2, id .. ": one dot per point with a mesh")
  end
  T.eq(count(s:match('<table id="points">.-</table>'), "<tr>"), 4, "header + a row per point")
  T.check(s:find("r.lua:3: &lt;boom&gt;", 1, true), "error text escaped")
  T.checkerr("manifest table expected", report.sweep_page, {}, sp)
end
-- }======

-- {====== the sweep page: series by the second axis, labels apart, rounded
-- ticks, an honest page when every point failed
do
  local function pt(i, target, ms, tri, avg, mn, dev)
    return { index = i, status = "ok", params = { target = target, min_stretch = ms },
      meshes = { { path = ("points/%03d/m.obj"):format(i), triangles = tri, stretch_avg = avg, stretch_min = mn,
        size_max = 1, valence_max = 7, hausdorff_rel = dev } } }
  end
  -- two points almost on top of each other per target: their labels must not collide
  local man = { digest = "d", recipe = { path = "sweep.lua" },
    grid = { { name = "target", values = { 1500, 3000 } }, { name = "min_stretch", values = { 0.3, 0.5 } } },
    points = { pt(0, 1500, 0.3, 1500, 0.7412, 0.3101, 0.0041), pt(1, 1500, 0.5, 1502, 0.7433, 0.3105, 0.0042),
      pt(2, 3000, 0.3, 3000, 0.7671, 0.3302, 0.0023), pt(3, 3000, 0.5, 3001, 0.7688, 0.5013, 0.0024) } }
  local sp = path("sweep2.html")
  report.sweep_page(man, sp)
  local s = T.readfile(sp)
  local legend = s:match('<div class="series%-legend" id="series%-legend">(.-)</div>')
  T.check(legend, "a legend for the second axis")
  T.eq(count(legend or "", 'class="swatch"'), 2, "one entry per value")
  T.check(legend and legend:find("min_stretch = 0.3", 1, true) and legend:find("min_stretch = 0.5", 1, true),
    "named by value")
  local c1, c2 = legend:match('background:(#%x+).-background:(#%x+)')
  T.check(c1 and c2 and c1 ~= c2, "two colours")
  for _, id in ipairs { "sweep-stretch-avg", "sweep-stretch-min", "sweep-deviation" } do
    local svg = s:match('<svg id="' .. id:gsub("%p", "%%%0") .. '".-</svg>')
    T.eq(count(svg, '<circle class="dot" style="fill:' .. c1 .. '"'), 2, id .. ": min_stretch 0.3 in its colour")
    T.eq(count(svg, '<circle class="dot" style="fill:' .. c2 .. '"'), 2, id .. ": min_stretch 0.5 in its colour")
    T.eq(count(svg, '<polyline class="series"'), 2, id .. ": a line per series")
    nice_axis(chart_ticks(svg, "xtick"), id .. " x")
    nice_axis(chart_ticks(svg, "ytick"), id .. " y")
    -- label boxes (6 px a character, 10 px high, as placed) overlap no other label
    local boxes = {}
    for x, y, t in svg:gmatch('<text x="([%d.-]+)" y="([%d.-]+)" class="dotlabel">([^<]*)</text>') do
      x, y = tonumber(x), tonumber(y)
      boxes[#boxes + 1] = { x, y - 8, x + 6 * #t, y + 2 }
    end
    T.check(#boxes >= 2, id .. ": labels placed: " .. #boxes)
    for i = 1, #boxes do
      for j = i + 1, #boxes do
        local a, b = boxes[i], boxes[j]
        T.check(not (a[1] < b[3] and b[1] < a[3] and a[2] < b[4] and b[2] < a[4]), id .. ": labels " .. i .. " and "
          .. j .. " apart")
      end
    end
  end
  T.check(s:find('id="counts">4 points: 4 ok, 0 failed', 1, true), "counts")
  -- one axis: no legend, one colour
  report.sweep_page({ grid = { { name = "target", values = { 1, 2 } } }, points = { pt(0, 1, nil, 10, 0.7, 0.3, 0.01),
    pt(1, 2, nil, 20, 0.8, 0.4, 0.02) } }, sp)
  s = T.readfile(sp)
  T.check(not s:find("id=\"series-legend\"", 1, true), "one axis: no legend")
  -- every point failed: no charts, no invented axis, words that count right
  local failed = { grid = { { name = "target", values = { 1, 2, 3, 4 } } }, points = {} }
  for i = 0, 3 do
    failed.points[i + 1] = { index = i, status = "failed", params = { target = i + 1 }, meshes = {},
      error = "sweep.lua:3: target: integer expected, got nil" }
  end
  report.sweep_page(failed, sp)
  s = T.readfile(sp)
  T.check(s:find('id="counts">4 points: 0 ok, 4 failed', 1, true), "all failed: counted")
  T.check(s:find('<p class="failed" id="no%-results"><b>All 4 points failed%.</b> No point saved a mesh'),
    "all failed: said plainly")
  T.check(not s:find("<svg", 1, true), "no charts")
  T.check(not s:find("-0.06", 1, true) and not s:find("1.06", 1, true), "no invented axis")
  T.eq(count(s:match('<table id="points">.-</table>'), "<tr>"), 5, "the table still lists the points")
  T.eq(count(s, "integer expected, got nil"), 4, "with their reasons")
  failed.points = { failed.points[1] }
  report.sweep_page(failed, sp)
  s = T.readfile(sp)
  T.check(s:find('id="counts">1 point: 0 ok, 1 failed', 1, true), "one point: singular")
  T.check(s:find("<b>The point failed.</b>", 1, true), "one point failed")
  T.check(not s:find("1 points", 1, true), "never '1 points'")
  os.remove(sp)
end
-- }======

-- {====== femlod report MESH
do
  local small = path("fan2k.obj")
  mesh:save(small)
  local html = path("cli.html")
  os.remove(html)
  local code, out, err = run("report", small, "--reference", P.shared .. "/fandisk.obj", "--html", html)
  T.eq(code, 0, "report exit: " .. err)
  T.eq(err, "", "nothing on stderr")
  T.check(out:find("^report_fan2k%.obj: 2000 triangles, 1002 vertices\n"), "text report first")
  T.check(out:find("\n  hausdorff   [%d.e-]+ %("), "the deviation")
  T.check(out:find("\nmodel %(H x W x D%) | state | elements |"), "Table 1 header")
  T.check(out:find("\nfandisk%.obj %([^)]*%) | reference | 12946 | "), "reference row")
  T.check(out:find("\nreport_fan2k%.obj %([^)]*%) | result | 2000 | "), "result row")
  T.check(out:find("\n" .. html:gsub("%p", "%%%0") .. ": written %(with the 3D view%)\n$"), "page line")
  T.check((T.readfile(html) or ""):find("<model-viewer", 1, true), "the page")
  code, out = run("report", small, "--html", html, "--no-viewer")
  T.eq(code, 0, "--no-viewer")
  T.check(out:find("written %(without the 3D view%)"), out)
  T.check(not out:find("reference"), "no reference row without --reference")
  code, out = run("-q", "report", small)
  T.eq(code, 0, "-q report")
  T.eq(out, "", "-q prints nothing")
  local usage = R.usage
  usage("femlod: missing a mesh file", "report")
  usage("femlod: report: MESH comes first, then the options", "report", "--html", "x.html")
  usage("femlod: --html needs a value", "report", small, "--html")
  usage("femlod: option given twice: '--html'", "report", small, "--html", "a.html", "--html=b.html")
  usage("femlod: unknown option '--htm'; did you mean --html?", "report", small, "--htm=x")
  usage("femlod: --reference: file name expected, got ''", "report", small, "--reference=")
  code, out, err = run("report", P.tmp .. "/missing.obj")
  T.eq(code, 1, "missing mesh: exit 1")
  T.eq(err, "femlod: " .. P.tmp .. "/missing.obj: cannot open: No such file or directory\n", "names the file")

  -- $FEMLOD_MODEL_VIEWER: a readable file is the viewer inlined, one that
  -- cannot be read an error naming the variable and its value (never
  -- another copy taken silently); empty is unset; pages without the view
  -- do not look at it.
  local function with_env(value, ...)
    local parts = { "FEMLOD_MODEL_VIEWER=" .. quote(value), quote(P.femlod) }
    for i = 1, select("#", ...) do parts[#parts + 1] = quote((select(i, ...))) end
    return R.sh(table.concat(parts, " "))
  end
  local custom = path("custom_viewer.js")
  T.writefile(custom, "console.log('femlod test viewer');\n")
  os.remove(html)
  code, out, err = with_env(custom, "report", small, "--html", html)
  T.eq(code, 0, "FEMLOD_MODEL_VIEWER set to a file: " .. err)
  T.check((T.readfile(html) or ""):find("console.log('femlod test viewer');", 1, true),
    "FEMLOD_MODEL_VIEWER: that file is the viewer on the page")
  for _, bad in ipairs { { P.tmp .. "/no_such_viewer.js", "No such file or directory" },
    { P.tmp, "Is a directory" } } do
    os.remove(html)
    code, out, err = with_env(bad[1], "report", small, "--html", html)
    T.eq(code, 1, "FEMLOD_MODEL_VIEWER=" .. bad[1] .. ": exit 1")
    T.eq(err, "femlod: FEMLOD_MODEL_VIEWER is '" .. bad[1] .. "', which cannot be read (" .. bad[2]
      .. "): set it to the path of model-viewer.min.js, or unset it to use femlod's own copy\n",
      "FEMLOD_MODEL_VIEWER=" .. bad[1] .. ": the variable, its value and why")
    T.check(not T.exists(html), "no page with a bad FEMLOD_MODEL_VIEWER")
  end
  code, out, err = with_env(P.tmp .. "/no_such_viewer.js", "report", small, "--html", html, "--no-viewer")
  T.eq(code, 0, "--no-viewer does not look at FEMLOD_MODEL_VIEWER: " .. err)
  code, out, err = with_env("", "report", small, "--html", html)
  T.eq(code, 0, "FEMLOD_MODEL_VIEWER empty: femlod's own copy: " .. err)
  T.check((T.readfile(html) or ""):find("<model-viewer", 1, true), "empty FEMLOD_MODEL_VIEWER: the page has its view")
  -- In a recipe: at the line that asked for the page.
  local rp = path("viewer_env.lua")
  T.writefile(rp, "local m <close> = femlod.load(params.mesh)\nfemlod.report(m, { html = params.html })\n")
  code, out, err = with_env(P.tmp .. "/no_such_viewer.js", "run", rp, "mesh=" .. small, "html=" .. html)
  T.eq(code, 1, "recipe with a bad FEMLOD_MODEL_VIEWER: exit 1")
  T.check(err:find("^femlod: " .. rp:gsub("%p", "%%%0") .. ":2: FEMLOD_MODEL_VIEWER is '"), "at the recipe's line: " .. err)
  os.remove(custom)
  os.remove(html)
  os.remove(small)
end
-- }======

T.summary("test_report")
