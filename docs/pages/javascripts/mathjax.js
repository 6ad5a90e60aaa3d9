// MathJax 2 set-up for pymdownx.arithmatex (generic mode): typeset only the spans and
// blocks arithmatex marks, with the TeX fonts the site serves (no image fonts).
window.MathJax = {
  tex2jax: {
    inlineMath: [["\\(", "\\)"]],
    displayMath: [["\\[", "\\]"]],
    processEscapes: true,
    processEnvironments: true,
    ignoreClass: ".*|",
    processClass: "arithmatex"
  },
  "HTML-CSS": { availableFonts: ["TeX"], imageFont: null },
  showMathMenu: false
};
