"""Reading photos (JPEG, PNG, HEIC, TIFF, WebP, BMP; EXIF orientation and focal length) and writing images."""
