// Display equations that fit the content column.
//
// MathJax 3 does not break long formulas into lines, so a display equation wider than the
// column would be cut at its edge.  After MathJax has typeset the page, and again whenever the
// window changes width, each display equation wider than its box is set in a smaller font so
// that it fits, down to MIN_SCALE of its size; one that would need less (a long formula on a
// phone) keeps MIN_SCALE and scrolls sideways in its own box (class symrb-math-scroll).
// An inline formula wider than the column (long ones in API docstrings, on a phone) cannot
// shrink without shrinking its line: it scrolls sideways in its own box (symrb.css gives it
// max-width: 100%), and gets the same class, so that the test can tell.
// When done, <html data-symrb-math-fit="W"> records the window width W it was done for, which
// the browser test (tests/test_book_browser.py) waits for before it measures.
(function () {
  "use strict";
  const MIN_SCALE = 0.6;

  function fit() {
    const containers = document.querySelectorAll('mjx-container[display="true"]');
    containers.forEach((c) => {
      c.style.fontSize = "";
      c.classList.remove("symrb-math-scroll");
    });
    containers.forEach((c) => {
      const math = c.querySelector(":scope > mjx-math");
      if (!math) return;
      const need = math.getBoundingClientRect().width;
      const have = c.clientWidth;
      if (!need || !have || need <= have) return;
      const size = parseFloat(getComputedStyle(c).fontSize);
      const scale = Math.max(MIN_SCALE, (have - 2) / need);
      c.style.fontSize = (size * scale).toFixed(2) + "px";
      if (scale === MIN_SCALE && c.scrollWidth > c.clientWidth + 1) {
        c.classList.add("symrb-math-scroll");
      }
    });
    document.querySelectorAll('mjx-container:not([display="true"])').forEach((c) => {
      c.classList.remove("symrb-math-scroll");
      const box = c.parentElement && c.parentElement.closest("p, li, dd, dt, td, th, div");
      if (box && c.getBoundingClientRect().width > box.clientWidth + 1) {
        c.classList.add("symrb-math-scroll");
      }
    });
    document.documentElement.dataset.symrbMathFit = String(window.innerWidth);
  }

  function whenTypeset() {
    const mj = window.MathJax;
    if (mj && mj.startup && mj.startup.promise) {
      mj.startup.promise.then(fit);
    } else if (!document.querySelector('script[src*="mathjax" i]')) {
      fit(); // no math on this page
    } else {
      setTimeout(whenTypeset, 50);
    }
  }

  let pending = null;
  window.addEventListener("resize", () => {
    delete document.documentElement.dataset.symrbMathFit;
    clearTimeout(pending);
    pending = setTimeout(whenTypeset, 30);
  });
  if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", whenTypeset);
  } else {
    whenTypeset();
  }
})();
