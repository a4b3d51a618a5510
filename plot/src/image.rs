//! The RGB raster a PNG is encoded from.

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
    /// The colour at pixel (x, y), `None` outside the image.
    pub fn pixel(&self, x: usize, y: usize) -> Option<Rgb> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = 3 * (y * self.width + x);
        Some([self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]])
    }

    /// A `big_w`×`big_h` RGB raster reduced `k` times in each direction, each
    /// pixel the mean of its `k`×`k` block (the antialiasing of a figure drawn
    /// `k` times larger).
    pub(crate) fn reduced(big: &[u8], big_w: usize, big_h: usize, k: usize) -> Image {
        let (width, height) = (big_w / k, big_h / k);
        let mut pixels = vec![0u8; 3 * width * height];
        for y in 0..height {
            for x in 0..width {
                for c in 0..3 {
                    let mut sum = 0u32;
                    for dy in 0..k {
                        for dx in 0..k {
                            sum += u32::from(big[3 * ((y * k + dy) * big_w + x * k + dx) + c]);
                        }
                    }
                    pixels[3 * (y * width + x) + c] = ((sum + (k * k / 2) as u32) / (k * k) as u32) as u8;
                }
            }
        }
        Image {
            width,
            height,
            pixels,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduction_averages_each_block() {
        // 4x2 big pixels: a black and a white 2x2 block
        let mut big = vec![255u8; 3 * 4 * 2];
        for y in 0..2 {
            for x in 0..2 {
                big[3 * (y * 4 + x)..3 * (y * 4 + x) + 3].copy_from_slice(&[0, 0, 0]);
            }
        }
        big[3 * 2..3 * 3].copy_from_slice(&[0, 0, 0]); // one black pixel in the white block
        let img = Image::reduced(&big, 4, 2, 2);
        assert_eq!((img.width, img.height), (2, 1));
        assert_eq!(img.pixel(0, 0), Some([0, 0, 0]));
        assert_eq!(img.pixel(1, 0), Some([191, 191, 191]));
        assert_eq!(img.pixel(2, 0), None);
    }
}
