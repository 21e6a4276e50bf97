// The page's own CSS and JavaScript, inlined by interactive_page.cpp after three.js. They read the
// data from the <script id="quadrix-data" type="application/json"> element the C++ side writes.
#pragma once

namespace quadrix {

/// CSS of the page: the 3-D view fills the window, the side panel floats on the right.
extern const char* const kPageStyle;

/// First script of the page: records any JavaScript error (window 'error' events, console.error)
/// as data-error on <body> and in document.title, so a headless browser can see it.
extern const char* const kPageErrorHook;

/// The viewer: decodes the data, builds the three.js scene (points, quadric meshes, correspondence
/// lines), the side panel and the interactions, draws the first frame and then records
/// performance.now() as data-ready-ms on <body> and in document.title ("quadrix view ready N ms").
extern const char* const kPageScript;

}  // namespace quadrix
