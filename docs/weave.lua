--[[ weave.lua: the pandoc Lua filter that turns a chapter's README.md into
its page of the book (run by `make docs`, see the Makefile).

What it does to a page:
  * Excerpts. "<!-- excerpt FILE NAME -->" ... "<!-- end of excerpt -->"
    (FILE from the repository's root, NAME a C function, struct, typedef,
    enum or #define) holds, in the README, a caption and the code in a ```c
    block, written there by docs/excerpts.sh (`make excerpts`) so that the
    README shows the code on any Git host. The page shows the definition
    read from the source now, with the comment just above it: the page
    cannot show code the source no longer has, and a README whose code
    differs from it stops the build (so the README and the page agree, and
    excerpts.awk finds what find_definition finds). A fenced block of class
    `excerpt` with lines "FILE NAME" (what `make excerpts` turns into the
    above) is woven the same way. A name that is not found stops the build
    with the README's file and line.
  * Images. A README shows ../../docs/img/X.png, the committed copy of a
    figure the build makes (`make figures` refreshes them): build/out/X.png
    when docs/figures.txt names out/X.png, else build/plots/X.png from
    plots/X.gp. The build's own image is copied next to the page, and under
    it goes the command that made it (docs/figures.txt, or the plot's
    gnuplot script and the --data run that build/data/NAME.run records,
    quick or full). A hand-drawn diagram, docs/diagrams/X.svg, is copied as
    it is and named under it. An image that is missing (in the repository
    or the build), or has no command, stops the build.
  * Measured tables. Between "<!-- table NAME -->" and "<!-- end of table
    NAME -->" the page shows build/plots/NAME.md, the table `make plots`
    wrote from the data of this build's plot (docs/splice.sh).
  * Links. A link to another chapter's README.md goes to that chapter's page,
    one to a chapter's companion page (chapters/NN-name/going-further.md)
    to its woven page, NN-name.going-further.html;
    a link to a source file goes to the file in the repository; an #anchor
    must name a heading of the page.
  * The head of a chapter page: after the README's "Lecture topics", the
    slides it covers with their formulas (docs/lectures.md), and what changed
    since the previous chapter (hand-written there, plus the files and tests
    the chapter adds, counted here). The chapter's picture is shown even
    where the README does not show it, and the page must have its "Hard
    cases" and "Exercises" sections.
  * docs/coverage.md: every file, function, test and figure the table names
    must exist (see check_coverage); one that does not stops the build. On
    that page a function links to the chapter page whose excerpt shows it.

Metadata it reads (pandoc -M): page (chapter|index|coverage), chapter
(NN-name), chapters (all of them, in order), files (the chapter's sources),
build (the build directory, from the repository's root), docs (the output
directory, likewise), root (the repository's root, seen from the output
directory), figures, lectures (the two files named above), plots (the
gnuplot scripts: a chapter must show each of its plots), diagrams (the
numbers of the chapters whose slides draw their geometry: each must show a
diagram, docs/diagrams/*.svg).

Every page is also refused for a date (YYYY-MM-DD) or a path to ../shared:
the text is the lecture, readable from the repository alone.
]]

local stringify = pandoc.utils.stringify

-- A link the filter makes itself: already in the page's terms.
local function made_link(content, target)
  return pandoc.Link(content, target, "", pandoc.Attr("", { "woven" }))
end

local M = {}           -- metadata, as strings
local errors = {}      -- every problem found; the build fails if any
local source_file = "" -- the markdown file being woven
local source_lines = {}

local function fail(where, message)
  table.insert(errors, where .. ": " .. message)
end

local function read_file(path)
  local f = io.open(path, "rb")
  if not f then return nil end
  local text = f:read("a")
  f:close()
  return text
end

local function lines_of(text)
  local lines = {}
  for line in (text .. "\n"):gmatch("([^\n]*)\n") do
    table.insert(lines, line)
  end
  if lines[#lines] == "" then table.remove(lines) end
  return lines
end

local function file_exists(path)
  local f = io.open(path, "rb")
  if f then f:close() return true end
  return false
end

local function copy_file(from, to)
  local data = read_file(from)
  if not data then return false end
  local f = assert(io.open(to, "wb"))
  f:write(data)
  f:close()
  return true
end

-- The line of the source file on which `needle` first appears (at or after
-- line `from`), for messages that name file:line.
local function line_of(needle, from)
  for i = from or 1, #source_lines do
    if source_lines[i]:find(needle, 1, true) then return i end
  end
  return 0
end

local function where(needle)
  return source_file .. ":" .. line_of(needle)
end

-- "a/b/../c" -> "a/c"; paths stay relative to the repository's root.
local function normalize(path)
  local parts = {}
  for part in path:gmatch("[^/]+") do
    if part == ".." and #parts > 0 and parts[#parts] ~= ".." then
      table.remove(parts)
    elseif part ~= "." then
      table.insert(parts, part)
    end
  end
  return table.concat(parts, "/")
end

local function dirname(path)
  return path:match("^(.*)/[^/]*$") or "."
end

-- A path written in the source file, from the repository's root.
local function from_root(target)
  return normalize(dirname(source_file) .. "/" .. target)
end

local function split_words(s)
  local words = {}
  for w in s:gmatch("%S+") do table.insert(words, w) end
  return words
end

---------------------------------------------------------------- excerpts --

-- Skips C comments, strings and character literals while counting braces.
-- Returns the line on which the brace opened at or after (line, col) closes,
-- or nil when the first of '{' and ';' is ';' (a declaration, not a body).
local function matching_brace(lines, first)
  local depth, opened = 0, false
  local in_block_comment = false
  for i = first, #lines do
    local line = lines[i]
    local k = 1
    while k <= #line do
      local c = line:sub(k, k)
      local two = line:sub(k, k + 1)
      if in_block_comment then
        if two == "*/" then in_block_comment = false; k = k + 1 end
      elseif two == "/*" then
        in_block_comment = true; k = k + 1
      elseif two == "//" then
        break
      elseif c == '"' or c == "'" then
        local j = k + 1
        while j <= #line and line:sub(j, j) ~= c do
          if line:sub(j, j) == "\\" then j = j + 1 end
          j = j + 1
        end
        k = j
      elseif c == "{" then
        depth = depth + 1; opened = true
      elseif c == "}" then
        depth = depth - 1
        if opened and depth == 0 then return i end
      elseif c == ";" and not opened then
        return nil
      end
      k = k + 1
    end
  end
  return nil
end

-- The comment block ending just above line `start` (if any) begins here.
local function comment_start(lines, start)
  local i = start - 1
  if i >= 1 and lines[i]:match("%*/%s*$") then
    while i >= 1 and not lines[i]:find("/*", 1, true) do i = i - 1 end
    return math.max(i, 1)
  end
  local j = start
  while j - 1 >= 1 and lines[j - 1]:match("^%s*//") do j = j - 1 end
  return j
end

local function escape_pattern(s)
  return (s:gsub("[%^%$%(%)%%%.%[%]%*%+%-%?]", "%%%0"))
end

-- Finds the definition of `name` in the lines of a C file. Returns the first
-- and last line of the definition (its leading comment included), or nil.
local function find_definition(lines, name)
  local n = escape_pattern(name)
  for i, line in ipairs(lines) do
    -- #define NAME ...
    if line:match("^#%s*define%s+" .. n .. "[%s%(]") or line:match("^#%s*define%s+" .. n .. "$") then
      local last = i
      while lines[last]:match("\\%s*$") and last < #lines do last = last + 1 end
      return comment_start(lines, i), last
    end
    -- enum { NAME = 4 };  a constant in a one-line enum
    if line:match("^enum%s*{[^}]*%f[%w_]" .. n .. "%s*=") then
      return comment_start(lines, i), i
    end
    -- } name;  closing a typedef of a struct, union or enum
    if line:match("^}%s*" .. n .. "%s*;") then
      local j = i
      while j >= 1 and not lines[j]:match("^typedef") do j = j - 1 end
      if j >= 1 then return comment_start(lines, j), i end
    end
    -- struct name { / enum name { / typedef struct name {
    if (line:match("^struct%s+" .. n .. "%s*{") or line:match("^enum%s+" .. n .. "%s*{")
            or line:match("^union%s+" .. n .. "%s*{") or line:match("^typedef%s+%a+%s+" .. n .. "%s*{")) then
      local last = matching_brace(lines, i)
      if last then return comment_start(lines, i), last end
    end
    -- A function definition: its signature starts in column 0 and a body follows.
    if line:match("^[%a_]") and not line:match("^typedef")
       and (line:match("^" .. n .. "%s*%(") or line:match("[^%w_]" .. n .. "%s*%(")) then
      local open = line:find(n .. "%s*%(")
      local before = line:sub(1, open - 1)
      -- not a call inside an initializer, not a macro's use: the name must
      -- follow the return type directly
      if not before:find("[=,(]") then
        local last = matching_brace(lines, i)
        if last then return comment_start(lines, i), last end
      end
    end
    -- enum { NAME = ... } or a constant: `static const float NAME = ...;`
    if line:match("^%s+" .. n .. "%s*=") or line:match("^static%s+const%s+[%w_ ]+%s" .. n .. "%s*=") then
      local first, last = i, i
      while not lines[last]:find(";", 1, true) and not lines[last]:find(",%s*$")
            and not lines[last]:find(",%s*/[/*]") and last < #lines do
        last = last + 1
      end
      -- its comment sits just above it, in column 0 or indented
      local c = first - 1
      if c >= 1 and lines[c]:match("%*/%s*$") then
        while c >= 1 and not lines[c]:find("/*", 1, true) do c = c - 1 end
        first = c
      end
      return first, last
    end
  end
  return nil
end

-- A link to a file of the repository, from the output page (M.root is the
-- repository's root as seen from there).
local function source_link(path)
  return M.root .. "/" .. path
end

local definitions_cache = {}
local excerpt_ids = {}

-- The definition of `name` in `path` as the page shows it (its label and
-- code), or nil, having said why; `at` is where the README asks for it.
-- `shown`, when given, is the code the README itself holds there
-- (docs/excerpts.sh wrote it): it must be the code read now.
local function excerpt_of(path, name, at, shown)
  local text = definitions_cache[path] or read_file(path)
  if not text then
    fail(at, "excerpt: no file " .. path)
    return nil
  end
  definitions_cache[path] = text
  local lines = lines_of(text)
  local first, last = find_definition(lines, name)
  if not first then
    fail(at, "excerpt: " .. name .. " is not defined in " .. path .. " any more")
    return nil
  end
  local code = table.concat(lines, "\n", first, last)
  if shown and shown ~= code then
    fail(at, "the excerpt of " .. name .. " differs from " .. path .. ": `make excerpts` writes it again")
  end
  local label = pandoc.Para({
    pandoc.Code(name), pandoc.Space(), pandoc.Str("in"), pandoc.Space(),
    made_link({ pandoc.Code(path) }, source_link(path)),
    pandoc.Str(", lines " .. first .. "–" .. last),
  })
  local id = "excerpt-" .. name
  if excerpt_ids[id] then id = "" end -- the first excerpt of a name is the one linked to
  excerpt_ids[id] = true
  return pandoc.Div({ label, pandoc.CodeBlock(code, pandoc.Attr("", { "c" })) }, pandoc.Attr(id, { "excerpt" }))
end

-- A block ```excerpt (lines "FILE NAME"), the form docs/excerpts.sh
-- replaces: woven as it stands.
local function excerpt_blocks(block)
  local out = {}
  for _, ref in ipairs(lines_of(block.text)) do
    if ref:match("%S") then
      local words = split_words(ref)
      local at = where(ref)
      if #words ~= 2 then
        fail(at, "an excerpt line is `FILE NAME` (from the repository's root), not `" .. ref .. "`")
      else
        table.insert(out, excerpt_of(words[1], words[2], at))
      end
    end
  end
  return out
end

-- An excerpt as the README holds it (docs/excerpts.sh): from "<!-- excerpt
-- FILE NAME -->" to "<!-- end of excerpt -->", a caption and the code in a
-- ```c block. The page shows the definition read from the source now, and
-- refuses a README whose code is not that.
local function splice_excerpts(blocks)
  local out, open = {}, nil
  for _, b in ipairs(blocks) do
    local text = b.t == "RawBlock" and b.text:gsub("%s+$", "") or ""
    local path, name = text:match("^<!%-%- excerpt (%S+) ([%w_]+) %-%->$")
    if open then
      if text == "<!-- end of excerpt -->" then
        local at = where("<!-- excerpt " .. open.path .. " " .. open.name .. " -->")
        if not open.code then fail(at, "the excerpt of " .. open.name .. " holds no code block: `make excerpts`") end
        table.insert(out, excerpt_of(open.path, open.name, at, open.code or ""))
        open = nil
      elseif b.t == "CodeBlock" then
        open.code = b.text
      end
    elseif path then
      open = { path = path, name = name }
    else
      table.insert(out, b)
    end
  end
  if open then fail(where("<!-- excerpt " .. open.path), "the excerpt of " .. open.name .. " has no `<!-- end of excerpt -->`") end
  return out
end

---------------------------------------------------------------- figures --

local figures = nil -- "out/ch01.png" -> command

local function load_figures()
  if figures then return figures end
  figures = {}
  local text = read_file(M.figures) or ""
  for _, line in ipairs(lines_of(text)) do
    if not line:match("^%s*#") and line:match("%S") then
      local img, cmd = line:match("^(%S+)%s+(.+)$")
      if img then figures[img] = cmd end
    end
  end
  return figures
end

-- The command that makes the image at build/`rel` (rel = out/X.png or
-- plots/X.png), as inlines, or nil.
local function figure_command(rel)
  local cmd = load_figures()[rel]
  if cmd then return { pandoc.Code(cmd) } end
  local plot = rel:match("^plots/(.+)%.png$")
  if plot and file_exists("plots/" .. plot .. ".gp") then
    local number = plot:match("^ch(%d%d)_")
    local program = nil
    for _, c in ipairs(split_words(M.chapters or "")) do
      if number and c:sub(1, 2) == number then program = c end
    end
    -- the run that wrote the data, as make plots recorded it: "quick" or
    -- "full", a tab, the command (build/data/chNN.run, accel.run)
    local record = read_file(M.build .. "/data/" .. (number and ("ch" .. number) or "accel") .. ".run") or ""
    local mode, run = record:match("^(%a+)\t([^\n]+)")
    if not run and program then mode, run = "full", "build/bin/" .. program .. " --data build/data" end
    if not run and plot:match("^accel_") then mode, run = "full", "make bench" end
    local inl = {}
    if run then
      table.insert(inl, pandoc.Strong({ pandoc.Str(mode == "quick" and "Quick data" or "Full data") }))
      table.insert(inl, pandoc.Str(": "))
      table.insert(inl, pandoc.Code(run))
      table.insert(inl, pandoc.Str(", then "))
    end
    table.insert(inl, pandoc.Code("gnuplot -e \"data_dir='build/data'; plot_dir='build/plots'\" plots/"
                                  .. plot .. ".gp"))
    table.insert(inl, pandoc.Str(" (both part of "))
    table.insert(inl, pandoc.Code("make plots"))
    if mode == "quick" then
      table.insert(inl, pandoc.Str("; quick runs, rough curves: "))
      table.insert(inl, pandoc.Code("make plots FULL=1"))
      table.insert(inl, pandoc.Str(" for the full size"))
    end
    table.insert(inl, pandoc.Str(")"))
    return inl
  end
  return nil
end

local shown_images = {}

-- Where the build makes the figure docs/img/NAME: out/NAME (a program's
-- picture, figures.txt) or plots/NAME (a gnuplot script's), or nil.
local function figure_rel(name)
  if load_figures()["out/" .. name] then return "out/" .. name end
  if file_exists("plots/" .. name:gsub("%.png$", ".gp")) then return "plots/" .. name end
  return nil
end

-- Copies the image into the output directory and points the page at the copy.
-- Returns the command inlines for the caption.
local function weave_image(img)
  local src = img.src
  if src:match("^%a+://") then
    fail(where(src), "the book is read offline: no remote image " .. src)
    return nil
  end
  local path = from_root(src)
  -- a diagram drawn by hand: copied as it is
  local diagram = path:match("^docs/diagrams/([^/]+%.svg)$")
  if diagram then
    if not copy_file(path, M.docs .. "/img/" .. diagram) then
      fail(where(src), "no diagram " .. path)
    end
    img.src = "img/" .. diagram
    img.classes:insert("woven")
    -- the caption reads "made by hand: docs/diagrams/X.svg" (book.css adds "made by")
    return { pandoc.Str("hand: "), made_link({ pandoc.Code(path) }, source_link(path)) }
  end
  -- a committed copy of a figure (docs/img/, made by make figures): the
  -- page shows the build's own, with its command
  local rel = path:match("^build/(.+)$")
  local committed = path:match("^docs/img/([^/]+%.png)$")
  if committed then
    if not file_exists(path) then
      fail(where(src), path .. " is not in the repository (make figures copies it there)")
    end
    rel = figure_rel(committed)
    if not rel then
      fail(where(src), "no command makes " .. path .. ": add out/" .. committed .. " to " .. M.figures
                       .. " or write plots/" .. committed:gsub("%.png$", ".gp"))
      return nil
    end
  end
  if not rel then
    fail(where(src), "images are figures the build makes (docs/img/, a copy of build/out or build/plots) "
                     .. "or diagrams (docs/diagrams/*.svg), not " .. path)
    return nil
  end
  local actual = M.build .. "/" .. rel
  local name = rel:gsub("/", "_")
  shown_images[rel] = true
  local cmd = figure_command(rel)
  if not cmd then
    fail(where(src), "no command makes " .. rel .. ": add it to " .. M.figures)
  end
  if not copy_file(actual, M.docs .. "/img/" .. name) then
    fail(where(src), "the image " .. actual .. " has not been made (run its command, or make docs)")
  end
  img.src = "img/" .. name
  img.classes:insert("woven")
  return cmd
end

-- A paragraph of images gets a caption per image: the command that made it.
local function weave_image_para(para)
  local images = {}
  for _, inline in ipairs(para.content) do
    if inline.t == "Image" then table.insert(images, inline) end
  end
  if #images == 0 then return nil end
  local caption = {}
  for k, img in ipairs(images) do
    local cmd = weave_image(img)
    if cmd then
      if #caption > 0 then table.insert(caption, pandoc.LineBreak()) end
      if #images > 1 then
        table.insert(caption, pandoc.Emph({ pandoc.Str(stringify(img.caption) .. ":") }))
        table.insert(caption, pandoc.Space())
      end
      for _, c in ipairs(cmd) do table.insert(caption, c) end
    end
  end
  local figure = pandoc.Div({ para, pandoc.Div({ pandoc.Plain(caption) }, pandoc.Attr("", { "command" })) },
                            pandoc.Attr("", { "figure" }))
  return figure
end

---------------------------------------------------------------- links --

local chapter_pages = {}

local function weave_link(link)
  local target = link.target
  if link.classes:includes("woven") then return link end
  if target:match("^%a[%w+.-]*:") then return link end -- http:, mailto:
  if target:match("^#") then return link end         -- checked with the headings
  local path, anchor = target:match("^([^#]*)(#?.*)$")
  local full = from_root(path)
  local chapter = full:match("^chapters/([^/]+)/README%.md$") or full:match("^chapters/([^/]+)/?$")
  local companion_chapter, companion = full:match("^chapters/([^/]+)/([%w-]+)%.md$")
  if chapter then
    if not chapter_pages[chapter] then fail(where(target), "no chapter " .. chapter) end
    link.target = chapter .. ".html" .. anchor
  elseif companion_chapter and file_exists(full) then
    -- a chapter's companion page (going-further.md): woven beside it
    link.target = companion_chapter .. "." .. companion .. ".html" .. anchor
  elseif full == "docs/coverage.md" then
    link.target = "coverage.html" .. anchor
  elseif full == "docs/index.md" or full == "README.md" then
    link.target = "index.html" .. anchor
  elseif full:match("^build/") then
    link.target = M.root .. "/" .. M.build .. full:sub(6) .. anchor
  else
    if not file_exists(full) and not file_exists(full .. "/.") then
      fail(where(target), "the link points to " .. full .. ", which does not exist")
    end
    link.target = M.root .. "/" .. full .. anchor
  end
  return link
end

---------------------------------------------------------------- coverage --

-- Cells of a table row written `| a | b |`.
local function row_cells(line)
  local cells = {}
  local body = line:match("^%s*|(.*)|%s*$")
  if not body then return nil end
  for cell in (body .. "|"):gmatch("([^|]*)|") do
    table.insert(cells, cell)
  end
  return cells
end

local function code_spans(cell)
  local spans = {}
  for s in cell:gmatch("`([^`]+)`") do table.insert(spans, s) end
  return spans
end

-- Every row of the coverage table names a concept and where it lives: the
-- file, the function(s) in that file, the test(s) and the figure. Each must
-- exist; nothing may be left empty.
local function check_coverage()
  local columns = nil
  local rows = 0
  for i, line in ipairs(source_lines) do
    local cells = row_cells(line)
    if cells then
      local at = source_file .. ":" .. i
      if not columns then
        columns = {}
        for k, c in ipairs(cells) do columns[k] = c:match("^%s*(.-)%s*$"):lower() end
        local want = { "concept", "lecture", "file", "function", "test", "figure" }
        for k, w in ipairs(want) do
          if columns[k] ~= w then fail(at, "the table's columns are " .. table.concat(want, ", ")) break end
        end
      elseif not line:match("^%s*|[%s:|-]+|%s*$") then
        rows = rows + 1
        local concept = cells[1]:match("^%s*(.-)%s*$")
        local file = code_spans(cells[3] or "")
        local fns = code_spans(cells[4] or "")
        local tests = code_spans(cells[5] or "")
        local figs = code_spans(cells[6] or "")
        if #file ~= 1 then fail(at, concept .. ": name one file") end
        if #fns == 0 then fail(at, concept .. ": no function") end
        if #tests < 2 then fail(at, concept .. ": name the test file, then the test") end
        if #figs == 0 then fail(at, concept .. ": no figure") end
        if #file == 1 then
          local text = read_file(file[1])
          if not text then
            fail(at, concept .. ": no file " .. file[1])
          else
            local lines = lines_of(text)
            for _, fn in ipairs(fns) do
              local name = fn:gsub("%(%)$", "")
              if not find_definition(lines, name) then
                fail(at, concept .. ": " .. name .. " is not defined in " .. file[1])
              end
            end
          end
        end
        if #tests >= 2 then
          local text = read_file(tests[1])
          if not text then
            fail(at, concept .. ": no test file " .. tests[1])
          else
            for k = 2, #tests do
              local t = escape_pattern(tests[k])
              if not (text:find("static void " .. t .. "%(") and text:find("cmocka_unit_test[%w_]*%(" .. t .. "[,)]")) then
                fail(at, concept .. ": " .. tests[k] .. " is not a test that " .. tests[1] .. " runs")
              end
            end
          end
        end
        for _, fig in ipairs(figs) do
          if fig:match("^docs/diagrams/[^/]+%.svg$") then
            if not file_exists(fig) then fail(at, concept .. ": no diagram " .. fig) end
          elseif not figure_command(fig) then
            fail(at, concept .. ": no command makes the figure " .. fig)
          elseif not file_exists(M.build .. "/" .. fig) then
            fail(at, concept .. ": the figure " .. M.build .. "/" .. fig .. " has not been made")
          end
        end
      end
    end
  end
  if rows == 0 then fail(source_file, "the coverage table has no rows") end
end

-- Where each function is shown: "FILE NAME" -> the page and anchor of the
-- first excerpt of it in a chapter's text.
local excerpt_pages = nil
local function find_excerpt(file, name)
  if not excerpt_pages then
    excerpt_pages = {}
    for _, c in ipairs(split_words(M.chapters or "")) do
      local text = read_file("chapters/" .. c .. "/README.md") or ""
      local inside = false
      for _, line in ipairs(lines_of(text)) do
        local file, name = line:match("^<!%-%- excerpt (%S+) ([%w_]+) %-%->$")
        if file and not excerpt_pages[file .. " " .. name] then
          excerpt_pages[file .. " " .. name] = c .. ".html#excerpt-" .. name
        elseif line:match("^```excerpt%s*$") then
          inside = true
        elseif inside and line:match("^```") then
          inside = false
        elseif inside then
          local w = split_words(line)
          if #w == 2 and not excerpt_pages[line] then excerpt_pages[w[1] .. " " .. w[2]] = c .. ".html#excerpt-" .. w[2] end
        end
      end
    end
  end
  return excerpt_pages[file .. " " .. name]
end

local coverage_file = nil -- the file cell of the row being woven
local thumbnailed = {}    -- the figures already shown as a thumbnail

-- A name in a narrow cell, breakable only after "/" and "_" (never
-- mid-word): <code> with <wbr> there.
local function breakable_code(t)
  local html = t:gsub("&", "&amp;"):gsub("<", "&lt;"):gsub(">", "&gt;")
  html = html:gsub("([/_])", "%1<wbr>")
  return pandoc.RawInline("html", "<code>" .. html .. "</code>")
end

-- In the coverage page, files become links to the source, figures
-- thumbnails (each figure once: where it comes again, its name links to
-- it), and functions links to the chapter page that shows them.
local function weave_coverage_cell_code(code)
  local t = code.text
  if coverage_file and t:match("^[%a_][%w_]*$") then
    local target = find_excerpt(coverage_file, t)
    if target then return made_link({ breakable_code(t) }, target) end
    return breakable_code(t)
  end
  local from = nil
  if t:match("^out/.+%.png$") or t:match("^plots/.+%.png$") then from = M.build .. "/" .. t end
  if t:match("^docs/diagrams/[^/]+%.svg$") then from = t end
  if from then
    local name = t:gsub("^docs/diagrams/", "diagram_"):gsub("/", "_")
    if thumbnailed[t] then return made_link({ breakable_code(t) }, "img/" .. name) end
    thumbnailed[t] = true
    copy_file(from, M.docs .. "/img/" .. name)
    return made_link({ pandoc.Image({ pandoc.Str(t) }, "img/" .. name, "", pandoc.Attr("", { "thumb" })) },
                       "img/" .. name)
  end
  if t:match("^[%w_-]+/.+%.[ch]$") or t:match("^tests/.+%.c$") then
    if not t:match("^tests/") then coverage_file = t end
    return made_link({ breakable_code(t) }, source_link(t))
  end
  if M.page == "coverage" and t:match("^[%a_][%w_]*$") then return breakable_code(t) end
  return nil
end

---------------------------------------------------------------- the head --

local lectures_doc = nil

-- The blocks under "## NN-name" in docs/lectures.md.
local function lecture_section(chapter)
  if not lectures_doc then
    local text = read_file(M.lectures)
    if not text then fail(M.lectures, "missing") return {} end
    lectures_doc = pandoc.read(text, "markdown")
  end
  local blocks, inside = {}, false
  for _, b in ipairs(lectures_doc.blocks) do
    if b.t == "Header" and b.level == 2 then
      inside = stringify(b.content) == chapter
    elseif inside then
      table.insert(blocks, b)
    end
  end
  return blocks
end

local function count_tests(chapter)
  local text = read_file("tests/test_ch" .. chapter:sub(1, 2) .. ".c") or ""
  local n = 0
  for _ in text:gmatch("cmocka_unit_test[%w_]*%(") do n = n + 1 end
  return n
end

local function previous_chapter(chapter)
  local prev = nil
  for _, c in ipairs(split_words(M.chapters or "")) do
    if c == chapter then return prev end
    prev = c
  end
  return nil
end

local function next_chapter(chapter)
  local found = false
  for _, c in ipairs(split_words(M.chapters or "")) do
    if found then return c end
    if c == chapter then found = true end
  end
  return nil
end

local function nav_bar(chapter)
  local inl = { made_link({ pandoc.Str("The book") }, "index.html") }
  local prev, nxt = previous_chapter(chapter), next_chapter(chapter)
  if prev then
    table.insert(inl, pandoc.Str(" · ← "))
    table.insert(inl, made_link({ pandoc.Str(prev) }, prev .. ".html"))
  end
  if nxt then
    table.insert(inl, pandoc.Str(" · "))
    table.insert(inl, made_link({ pandoc.Str(nxt) }, nxt .. ".html"))
    table.insert(inl, pandoc.Str(" →"))
  end
  table.insert(inl, pandoc.Str(" · "))
  table.insert(inl, made_link({ pandoc.Str("coverage") }, "coverage.html"))
  return pandoc.Div({ pandoc.Plain(inl) }, pandoc.Attr("", { "nav" }))
end

-- "What changed": the hand-written words from lectures.md, then what the
-- chapter adds, read from the tree.
local function changes_blocks(chapter, section)
  local blocks = {}
  local prev = previous_chapter(chapter)
  local files = {}
  for _, f in ipairs(split_words(M.files or "")) do
    table.insert(files, made_link({ pandoc.Code(f) }, source_link("chapters/" .. chapter .. "/" .. f)))
    table.insert(files, pandoc.Str(", "))
  end
  if #files > 0 then table.remove(files) end
  local tests = count_tests(chapter)
  local facts = { pandoc.Str("New in this chapter: ") }
  for _, f in ipairs(files) do table.insert(facts, f) end
  table.insert(facts, pandoc.Str("; " .. tests .. " tests in "))
  local tfile = "tests/test_ch" .. chapter:sub(1, 2) .. ".c"
  table.insert(facts, made_link({ pandoc.Code(tfile) }, source_link(tfile)))
  table.insert(facts, pandoc.Str(" ("))
  table.insert(facts, pandoc.Code("make test-ch" .. chapter:sub(1, 2)))
  table.insert(facts, pandoc.Str(")."))
  local title = prev and ("What changed since " .. prev) or "Where the book starts"
  table.insert(blocks, pandoc.Header(3, { pandoc.Str(title) }, pandoc.Attr("what-changed")))
  for _, b in ipairs(section) do table.insert(blocks, b) end
  table.insert(blocks, pandoc.Para(facts))
  return blocks
end

local function has_image(doc, rel)
  local found = false
  pandoc.walk_block(pandoc.Div(doc.blocks), {
    Image = function(img)
      local path = from_root(img.src)
      if path == "build/" .. rel or path == "docs/img/" .. rel:gsub("^%a+/", "") then found = true end
    end,
  })
  return found
end

-- A slide's formula is shown as the slide shows it: a display block, full
-- size, not an inline formula in small type (in the table of slides). A
-- formula that opens its cell, or has fractions, sums, integrals or
-- matrices, is one; a symbol inside a sentence of a cell stays inline.
local function is_built_up(tex)
  return tex:find("\\frac") or tex:find("\\int") or tex:find("\\sum") or tex:find("\\begin")
end

local function display_formulas(block)
  if block.t ~= "Table" then return block end
  local function displayed(p)
    for k, inline in ipairs(p.content) do
      local after = p.content[k + 1]
      local alone = k == 1 and (not after or (after.t == "Str" and after.text:match("^[;,]")))
      if inline.t == "Math" and inline.mathtype == "InlineMath" and (alone or is_built_up(inline.text)) then
        p.content[k] = pandoc.Math("DisplayMath", inline.text)
      end
    end
    return p
  end
  return pandoc.walk_block(block, { Plain = displayed, Para = displayed })
end

local function chapter_head(doc, chapter)
  local section = lecture_section(chapter)
  if #section == 0 then
    fail(M.lectures, "no section `## " .. chapter .. "` with the chapter's slides and changes")
  end
  -- lectures.md: everything before "### What changed" is the slides part.
  local slides, changed, in_changed = {}, {}, false
  for _, b in ipairs(section) do
    if b.t == "Header" and stringify(b.content):lower():match("^what changed") then
      in_changed = true
    elseif in_changed then
      table.insert(changed, b)
    else
      table.insert(slides, b)
    end
  end
  local blocks = { pandoc.Header(3, { pandoc.Str("The slides this chapter follows") }, pandoc.Attr("slides")) }
  for _, b in ipairs(slides) do table.insert(blocks, display_formulas(b)) end
  for _, b in ipairs(changes_blocks(chapter, changed)) do table.insert(blocks, b) end
  local number = chapter:sub(1, 2)
  if not has_image(doc, "out/ch" .. number .. ".png") then
    table.insert(blocks, pandoc.Para({ pandoc.Str("The picture this chapter's program makes:") }))
    local img = pandoc.Image({ pandoc.Str("chapter " .. number) }, "../../docs/img/ch" .. number .. ".png")
    table.insert(blocks, pandoc.Para({ img }))
  end
  return pandoc.Div(blocks, pandoc.Attr("", { "head" }))
end

-- "On this page": the chapter's sections, in order.
local function contents(doc)
  local items = {}
  for _, b in ipairs(doc.blocks) do
    if b.t == "Header" and b.level == 2 then
      table.insert(items, { pandoc.Plain({ made_link(b.content, "#" .. b.identifier) }) })
    end
  end
  if #items == 0 then return nil end
  return pandoc.Div({ pandoc.Para({ pandoc.Strong({ pandoc.Str("On this page") }) }), pandoc.OrderedList(items) },
                    pandoc.Attr("", { "contents" }))
end

---------------------------------------------------------------- the page --

local function check_sections(doc, chapter)
  local hard, exercises, last = false, false, nil
  for _, b in ipairs(doc.blocks) do
    if b.t == "Header" and b.level == 2 then
      local s = stringify(b.content):lower()
      if s:match("^hard cases") then hard = true end
      if s:match("^exercises") then exercises = true end
      last = s
    end
  end
  if not hard then fail(source_file, "a chapter notes its hard cases: no `## Hard cases ...` section") end
  if not exercises then fail(source_file, "a chapter ends with `## Exercises`: there is none") end
  if last and not last:match("^exercises") then
    fail(source_file, "a chapter ends with `## Exercises`, but its last section is `" .. last .. "`")
  end
end

-- The text is the lecture: no dates (a text that says when it was written
-- is a diary) and no path outside the repository (../shared).
local function check_timeless()
  for i, line in ipairs(source_lines) do
    local date = line:match("%d%d%d%d%-%d%d%-%d%d")
    if date then fail(source_file .. ":" .. i, "a date (" .. date .. "): the text is the lecture, not its history") end
    if line:find("../shared", 1, true) then
      fail(source_file .. ":" .. i, "../shared is outside the repository: a reader of the book does not have it")
    end
  end
end

-- A chapter whose slides draw its geometry (docs/lectures.md's chapters in
-- M.diagrams, by number) shows at least one diagram, docs/diagrams/*.svg.
local function check_diagram(doc, chapter)
  local number = chapter:sub(1, 2)
  local wanted = false
  for _, n in ipairs(split_words(M.diagrams or "")) do
    if n == number then wanted = true end
  end
  if not wanted then return end
  local found = false
  pandoc.walk_block(pandoc.Div(doc.blocks), {
    Image = function(img)
      if from_root(img.src):match("^docs/diagrams/.+%.svg$") then found = true end
    end,
  })
  if not found then
    fail(source_file, "the slides draw this chapter's geometry: show a diagram of it (docs/diagrams/*.svg)")
  end
end

-- A measured table (docs/splice.sh): the README holds the committed copy,
-- from the run that drew the committed figure; the page shows the table of
-- this build's run (build/plots/NAME.md), which drew this page's plot.
local function splice_tables(blocks)
  local out, skipping = {}, nil
  for _, b in ipairs(blocks) do
    local text = b.t == "RawBlock" and b.text:gsub("%s+$", "") or ""
    local name = text:match("^<!%-%- table ([%w_]+) %-%->$")
    if skipping then
      if text == "<!-- end of table " .. skipping .. " -->" then skipping = nil end
    elseif name then
      local md = read_file(M.build .. "/plots/" .. name .. ".md")
      if not md then fail(where("<!-- table " .. name), "no table " .. M.build .. "/plots/" .. name .. ".md (make plots)") end
      for _, t in ipairs(md and pandoc.read(md, "gfm").blocks or {}) do table.insert(out, t) end
      skipping = name
    else
      table.insert(out, b)
    end
  end
  return out
end

-- A path explorer (chapter 09's picture, clickable): the README holds
-- "<!-- path explorer NAME IMAGE -->" (invisible on a Git host); the page
-- shows IMAGE (build/IMAGE, out/chNN.png) with an SVG over it, and the
-- paths of build/data/NAME.json (docs/figures/explain_paths.py, from the
-- program's --explain) inline, with the script that draws the path of the
-- pixel clicked (docs/path_explorer.js, inline: nothing is fetched).
local function path_explorers(blocks)
  local out = {}
  for _, b in ipairs(blocks) do
    local text = b.t == "RawBlock" and b.text:gsub("%s+$", "") or ""
    local name, rel = text:match("^<!%-%- path explorer ([%w_]+) ([%w_/.]+) %-%->$")
    if name then
      local json = read_file(M.build .. "/data/" .. name .. ".json")
      local script = read_file("docs/path_explorer.js")
      local image = rel:gsub("/", "_")
      if not json then fail(where("<!-- path explorer " .. name), "no " .. M.build .. "/data/" .. name .. ".json (make docs makes it)") end
      if not script then fail(where("<!-- path explorer " .. name), "no docs/path_explorer.js") end
      if not copy_file(M.build .. "/" .. rel, M.docs .. "/img/" .. image) then
        fail(where("<!-- path explorer " .. name), "the image " .. M.build .. "/" .. rel .. " has not been made")
      end
      shown_images[rel] = true
      if json and script then
        table.insert(out, pandoc.RawBlock("html", table.concat({
          '<div class="path-explorer" id="path-explorer">',
          '<div class="path-explorer-stage"><img src="img/' .. image .. '" alt="the picture: click a pixel">',
          '<svg xmlns="http://www.w3.org/2000/svg" class="path-explorer-paths" preserveAspectRatio="none"></svg></div>',
          '<p class="path-explorer-note">Click the picture: the path of the nearest pixel explained is drawn.</p>',
          '<script type="application/json" id="path-explorer-data">' .. json:gsub("</", "<\\/") .. '</script>',
          '<script>' .. script .. '</script>',
          '</div>' }, "\n")))
      end
    else
      table.insert(out, b)
    end
  end
  return out
end

local function check_plots_shown(chapter)
  local number = chapter:sub(1, 2)
  for _, f in ipairs(split_words(M.plots or "")) do
    local name = f:match("^plots/(ch" .. number .. "_.+)%.gp$")
    if name and not shown_images["plots/" .. name .. ".png"] then
      fail(source_file, "the chapter's plot build/plots/" .. name .. ".png is not shown")
    end
  end
end

function Pandoc(doc)
  for k, v in pairs(doc.meta) do M[k] = stringify(v) end
  source_file = PANDOC_STATE.input_files[1]
  source_lines = lines_of(read_file(source_file) or "")
  for _, c in ipairs(split_words(M.chapters or "")) do chapter_pages[c] = true end
  local chapter = M.chapter ~= "" and M.chapter or nil

  if M.page == "coverage" then check_coverage() end

  -- the page's title: its first heading
  for _, b in ipairs(doc.blocks) do
    if b.t == "Header" and b.level == 1 then
      doc.meta.pagetitle = stringify(b.content)
      break
    end
  end

  -- Every chapter's exercises say how to do them.
  for i, b in ipairs(doc.blocks) do
    if chapter and b.t == "Header" and b.level == 2 and stringify(b.content):lower():match("^exercises") then
      local following = doc.blocks[i + 1]
      if not (following and stringify(following):lower():match("predict")) then
        table.insert(doc.blocks, i + 1, pandoc.Para({ pandoc.Emph({ pandoc.Str(
          "Each one: change one thing, predict what will change, run, compare.") }) }))
      end
      break
    end
  end

  doc.blocks = path_explorers(splice_excerpts(splice_tables(doc.blocks)))
  local blocks = {}
  local head_done = false
  if chapter then check_sections(doc, chapter) end
  if chapter then check_diagram(doc, chapter) end
  check_timeless()
  local toc = chapter and contents(doc)
  for i, b in ipairs(doc.blocks) do
    table.insert(blocks, b)
    -- the head goes after the README's "Lecture topics" paragraph
    if chapter and not head_done and b.t == "Para" and stringify(b):match("^Lecture topics") then
      table.insert(blocks, chapter_head(doc, chapter))
      if toc then table.insert(blocks, toc) end
      head_done = true
    end
  end
  if chapter and not head_done then
    fail(source_file, "a chapter opens with a `**Lecture topics:**` paragraph; there is none")
  end
  table.insert(blocks, 1, nav_bar(chapter))
  table.insert(blocks, nav_bar(chapter))

  -- excerpts, images, links
  local woven = {}
  for _, b in ipairs(blocks) do table.insert(woven, b) end
  local div = pandoc.walk_block(pandoc.Div(woven), {
    CodeBlock = function(cb)
      if cb.classes:includes("excerpt") then return excerpt_blocks(cb) end
      return nil
    end,
  })
  div = pandoc.walk_block(div, {
    Para = function(p) return weave_image_para(p) end,
  })
  -- images outside a paragraph of their own (in a table): copied, no caption
  div = pandoc.walk_block(div, {
    Image = function(img)
      if not img.classes:includes("woven") then weave_image(img) return img end
      return nil
    end,
  })
  div = pandoc.walk_block(div, {
    Link = function(l) return weave_link(l) end,
    Code = function(c)
      if M.page == "coverage" then return weave_coverage_cell_code(c) end
      return nil
    end,
  })
  if chapter then check_plots_shown(chapter) end

  -- every #anchor names a heading (or an element) of this page
  local ids = {}
  pandoc.walk_block(div, {
    Header = function(h) ids[h.identifier] = true end,
    Div = function(d) if d.identifier ~= "" then ids[d.identifier] = true end end,
  })
  pandoc.walk_block(div, {
    Link = function(l)
      local anchor = l.target:match("^#(.+)$")
      if anchor and not ids[anchor] then
        fail(where("#" .. anchor), "no heading #" .. anchor .. " on this page")
      end
    end,
  })

  if #errors > 0 then
    for _, e in ipairs(errors) do io.stderr:write(e .. "\n") end
    os.exit(1)
  end
  doc.blocks = div.content
  return doc
end
