#!/usr/bin/env bash
# Makes DejaVuSans-figures.ttf, the figures' font: DejaVu Sans 2.37 cut to the characters
# figures draw, without hinting or OpenType layout tables (the rasteriser uses neither; pair
# kerning comes from the legacy `kern` table, which is kept).
#
#   bash src/render/fonts/subset.sh [/path/to/DejaVuSans.ttf]
#
# Needs fonttools (`pip install fonttools`). The source font is Debian's fonts-dejavu-core
# 2.37-6 (/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf), the upstream release of
# https://dejavu-fonts.github.io/; its licence is LICENSE-DejaVu.txt beside this script.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
src="${1:-/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf}"
unicodes=(
  U+0020-007E # ASCII
  U+00A0-00FF # Latin-1: ° ± ² ³ · × µ é ...
  U+0131 U+0152-0153 U+0160-0161 U+0178 U+017D-017E # ı Œ œ Š š Ÿ Ž ž
  U+0391-03A1 U+03A3-03A9 U+03B1-03C9 U+03D1 U+03D5 U+03F5 # Greek: Σ Ω α β γ δ θ κ μ ... ϑ ϕ ϵ
  U+2010-2026 # dashes, quotes, bullet, ellipsis
  U+2032-2033 # ′ ″ (arcmin, arcsec)
  U+2070-209C # superscripts and subscripts ⁰ ¹ ⁻ ₀ ₛ ...
  U+2190-2193 # ← ↑ → ↓
  U+2202 U+2206 U+2207 U+2211 U+2212 U+2213 U+221A U+221D U+221E U+222B # ∂ ∆ ∇ ∑ − ∓ √ ∝ ∞ ∫
  U+2248 U+2260 U+2261 U+2264 U+2265 U+226A U+226B # ≈ ≠ ≡ ≤ ≥ ≪ ≫
  U+2299 U+2609 # ⊙ ☉ (solar masses)
  U+25A1 U+25CB U+25CF U+25A0 # □ ○ ● ■ (markers in text)
  U+FFFD # replacement character
)
pyftsubset "$src" \
  --unicodes="$(IFS=,; echo "${unicodes[*]}")" \
  --output-file="$here/DejaVuSans-figures.ttf" \
  --no-hinting --layout-features='' --legacy-kern \
  --drop-tables+=GSUB,GPOS,GDEF,FFTM,MATH --no-glyph-names \
  --name-IDs='*' --notdef-outline --recalc-bounds
ls -l "$here/DejaVuSans-figures.ttf"
