//! The RGB raster a figure is drawn on: pixels, rectangles, clipped thick or
//! dashed lines, and text in the embedded 8x8 bitmap font.

use font8x8::UnicodeFonts;

use crate::Rgb;

/// An RGB raster image, row-major, 3 bytes per pixel.
#[derive(Debug, Clone)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels, `3 * width * height` bytes.
    pub pixels: Vec<u8>,
}

impl Image {
    pub(crate) fn new(width: usize, height: usize) -> Self {
        Image {
            width,
            height,
            pixels: vec![255; 3 * width * height],
        }
    }

    /// The colour at pixel (x, y), `None` outside the image.
    pub fn pixel(&self, x: usize, y: usize) -> Option<Rgb> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = 3 * (y * self.width + x);
        Some([self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]])
    }

    pub(crate) fn put(&mut self, x: i64, y: i64, c: Rgb) {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return;
        }
        let i = 3 * (y as usize * self.width + x as usize);
        self.pixels[i..i + 3].copy_from_slice(&c);
    }

    pub(crate) fn fill_rect(&mut self, x0: i64, y0: i64, w: i64, h: i64, c: Rgb) {
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                self.put(x, y, c);
            }
        }
    }

    /// Bresenham line, `thick` pixels wide, skipping pixels outside `clip`.
    pub(crate) fn line(
        &mut self,
        a: (i64, i64),
        b: (i64, i64),
        c: Rgb,
        thick: i64,
        clip: Rect,
        dash: Option<&mut u32>,
    ) {
        let (mut x0, mut y0) = a;
        let (x1, y1) = b;
        let dx = (x1 - x0).abs();
        let dy = -(y1 - y0).abs();
        let sx = if x0 < x1 { 1 } else { -1 };
        let sy = if y0 < y1 { 1 } else { -1 };
        let mut err = dx + dy;
        let mut dash = dash;
        loop {
            let on = match dash.as_deref_mut() {
                Some(n) => {
                    *n += 1;
                    (*n / 8) % 2 == 0
                }
                None => true,
            };
            if on {
                for ox in 0..thick {
                    for oy in 0..thick {
                        let (px, py) = (x0 + ox - thick / 2, y0 + oy - thick / 2);
                        if clip.contains(px, py) {
                            self.put(px, py, c);
                        }
                    }
                }
            }
            if x0 == x1 && y0 == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x0 += sx;
            }
            if e2 <= dx {
                err += dx;
                y0 += sy;
            }
        }
    }

    /// Draws text with its top-left corner at (x, y), `scale` pixels per font pixel.
    pub(crate) fn text(&mut self, x: i64, y: i64, s: &str, c: Rgb, scale: i64) {
        let mut cx = x;
        for ch in s.chars() {
            let glyph = font8x8::BASIC_FONTS
                .get(ch)
                .or_else(|| font8x8::LATIN_FONTS.get(ch))
                .unwrap_or([0; 8]);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    if bits & (1 << col) != 0 {
                        self.fill_rect(cx + col * scale, y + row as i64 * scale, scale, scale, c);
                    }
                }
            }
            cx += 8 * scale;
        }
    }

    /// Draws text rotated 90° counter-clockwise, reading bottom to top, starting at (x, y) (bottom-left).
    pub(crate) fn text_vertical(&mut self, x: i64, y: i64, s: &str, c: Rgb) {
        let mut cy = y;
        for ch in s.chars() {
            let glyph = font8x8::BASIC_FONTS
                .get(ch)
                .or_else(|| font8x8::LATIN_FONTS.get(ch))
                .unwrap_or([0; 8]);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    if bits & (1 << col) != 0 {
                        self.put(x + row as i64, cy - col, c);
                    }
                }
            }
            cy -= 8;
        }
    }
}

/// Width in pixels of `s` drawn at `scale`.
pub(crate) fn text_width(s: &str, scale: i64) -> i64 {
    s.chars().count() as i64 * 8 * scale
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct Rect {
    pub(crate) x: i64,
    pub(crate) y: i64,
    pub(crate) w: i64,
    pub(crate) h: i64,
}

impl Rect {
    pub(crate) fn contains(&self, px: i64, py: i64) -> bool {
        px >= self.x && px < self.x + self.w && py >= self.y && py < self.y + self.h
    }
}
