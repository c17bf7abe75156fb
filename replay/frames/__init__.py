"""Camera frames: any image message decoded to numpy pixels with their colour order, and
frames encoded back into messages, through one table of decoders and one of encoders."""

from .decode import DECODERS, IMAGE_ENCODINGS, FrameStream, Raw, decode_frame, raw_encoding
from .encode import ENCODERS, decompress, encode_compressed, encode_image, natural_encoding
from .frame import Color, Frame
from .video import VideoDecoder, VideoEncoder, psnr_db

__all__ = [
    "DECODERS",
    "ENCODERS",
    "IMAGE_ENCODINGS",
    "Color",
    "Frame",
    "FrameStream",
    "Raw",
    "VideoDecoder",
    "VideoEncoder",
    "decode_frame",
    "decompress",
    "encode_compressed",
    "encode_image",
    "natural_encoding",
    "psnr_db",
    "raw_encoding",
]
