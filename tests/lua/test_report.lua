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
  T.eq(#r.histograms.size, 10, "10 size bins")
  T.eq(sum, 2000, "size histogram counts every triangle")
  T.eq(r.histograms.size_max, q.size_max, "size bins up to the largest size")
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
  T.eq(count(s, '<rect class="bar"'), 10 + 10 + #r.histograms.valence, "one bar per bin")
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
T.checkerr("test_report%.lua:%d+: bad argument #2 to 'report' %(unknown option 'htm'; valid: html, max_deviation, "
  .. "name, progress, reference, reference_name, title, viewer%)", function() femlod.report(mesh, { htm = "x" }) end)
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
  usage("femlod: report: unknown option '--htm' (valid: --reference, --html, --no-viewer, --max-deviation)", "report", small,
    "--htm=x")
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
