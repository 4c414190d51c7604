/* image.c -- the float RGB image: OpenEXR for the data, PNG for a preview.
 *
 * Structure:
 *   1. image_make / image_free.
 *   2. Encoding onto a descriptor the caller opened: the image knows its
 *      formats, not how files are put in place (image_file.c, on the
 *      program's side, writes through atomic_file: a temporary file renamed
 *      over the target, so a reader never sees a half-written one).
 *   3. EXR (the data) through the OpenEXR Core C API. We do our own file I/O
 *      (custom read/write callbacks on a descriptor) for two
 *      reasons: the write goes to the caller's descriptor, and the context's
 *      user_data stays ours, so the error handler can find the buffer to put
 *      OpenEXR's message in instead of letting the library print to stderr.
 *      Pixels go straight between our interleaved RGB buffer and the
 *      library, using the per-channel pointer / pixel stride / line stride.
 *   4. PNG (the preview): exposure, clamp, sRGB encode, 8 bits, stb.
 *   5. Error metrics (MSE, relative MSE), accumulated in double.
 */
#include "image.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <openexr.h>
#include <stb/stb_image_write.h>

/* The IMAGE_RELMSE_EPSILON named in image.h. 1e-2 is the usual value: it
 * keeps near-black reference pixels (ref^2 close to 0) from dominating the
 * mean, while errors in dark regions still weigh far more than in bright
 * ones. Not in the header because no caller needs to see it. */
static const double IMAGE_RELMSE_EPSILON = 1e-2;

/* Bytes from one pixel to the next in our interleaved RGB buffer: the pixel
 * stride we hand to OpenEXR (times the width, the line stride). */
enum { PIXEL_BYTES = 3 * (int)sizeof(float) };

/* ---- errors ------------------------------------------------------------ */

/* One line into err (which may be NULL / empty: callers that don't care). */
static void set_error(char *err, size_t err_size, const char *format, ...)
{
    if (err == NULL || err_size == 0)
        return;
    va_list args;
    va_start(args, format);
    vsnprintf(err, err_size, format, args);
    va_end(args);
}

/* ---- making an image --------------------------------------------------- */

image image_make(int width, int height)
{
    image img = {0, 0, NULL};
    if (width <= 0 || height <= 0)
        return img;
    /* width * height * 3 must fit in size_t before calloc multiplies by
     * sizeof(float) (which calloc itself checks). */
    size_t w = (size_t)width, h = (size_t)height;
    if (w > SIZE_MAX / 3 / sizeof(float) / h)
        return img;
    img.rgb = calloc(w * h * 3, sizeof(float));
    if (img.rgb != NULL) {
        img.width = width;
        img.height = height;
    }
    return img;
}

void image_free(image *img)
{
    if (img == NULL)
        return;
    free(img->rgb);
    img->rgb = NULL;
    img->width = img->height = 0;
}

/* Guard for the writers: the per-line byte stride must fit the int32 the
 * OpenEXR and stb interfaces take. */
static bool image_is_writable(const image *img)
{
    return img != NULL && img->rgb != NULL && img->width > 0 && img->height > 0 &&
           img->width <= INT32_MAX / PIXEL_BYTES;
}

/* ---- OpenEXR: our stream and error handler ------------------------------ */

/* The context's user_data: our descriptor, and the first message the
 * library reported (later ones are usually consequences of the first). */
typedef struct {
    int fd;
    char message[256];
} exr_stream;

static void exr_stream_note(exr_stream *s, const char *message)
{
    if (s->message[0] == '\0')
        snprintf(s->message, sizeof s->message, "%s", message);
}

/* The stream of the read or write this thread is doing, for the error
 * handler. The handler must not ask the context for its user data: a write
 * context holds its (non-recursive) lock while it writes the header, and a
 * write that fails there reports the error from inside that lock, so
 * exr_get_user_data would wait for itself forever. A full disk did exactly
 * that. Set by exr_initializer, cleared when the context is finished. */
static _Thread_local exr_stream *exr_current_stream;

/* Installed so OpenEXR never prints on its own: the message is kept for the
 * caller's err line instead. */
static void exr_error_handler(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    if (exr_current_stream != NULL)
        exr_stream_note(exr_current_stream, msg != NULL ? msg : exr_get_default_error_message(code));
}

/* The reason to show: what the library said, or failing that the generic
 * text for the code it returned. */
static const char *exr_stream_reason(const exr_stream *s, exr_result_t rv)
{
    return s->message[0] != '\0' ? s->message : exr_get_default_error_message(rv);
}

static int64_t exr_stream_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t size,
                                uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_stream *s = user;
    const unsigned char *bytes = buffer;
    uint64_t done = 0;
    while (done < size) {
        ssize_t n = pwrite(s->fd, bytes + done, (size_t)(size - done), (off_t)(offset + done));
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            /* Noted directly rather than only through error_cb, so the
             * strerror text is what ends up in err. */
            exr_stream_note(s, strerror(n < 0 ? errno : EIO));
            if (error_cb != NULL)
                error_cb(ctxt, EXR_ERR_WRITE_IO, "write failed");
            return -1;
        }
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static int64_t exr_stream_read(exr_const_context_t ctxt, void *user, void *buffer, uint64_t size,
                               uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_stream *s = user;
    unsigned char *bytes = buffer;
    uint64_t done = 0;
    while (done < size) {
        ssize_t n = pread(s->fd, bytes + done, (size_t)(size - done), (off_t)(offset + done));
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            exr_stream_note(s, strerror(errno));
            if (error_cb != NULL)
                error_cb(ctxt, EXR_ERR_READ_IO, "read failed");
            return -1;
        }
        if (n == 0)
            break; /* end of file: a short count, which the library checks */
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

/* Lets the library check offsets in the file against its real size. */
static int64_t exr_stream_size(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    const exr_stream *s = user;
    struct stat st;
    return fstat(s->fd, &st) == 0 ? (int64_t)st.st_size : -1;
}

static exr_context_initializer_t exr_initializer(exr_stream *stream)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_error_handler;
    init.user_data = stream;
    exr_current_stream = stream;
    init.read_fn = exr_stream_read;
    init.size_fn = exr_stream_size;
    init.write_fn = exr_stream_write;
    return init;
}

/* Where a channel lives inside an interleaved pixel: 0, 1, 2 for R, G, B;
 * -1 for any other channel (alpha, depth, ...), which we don't store. The
 * library lists channels alphabetically (B, G, R), so go by name. */
static int rgb_offset(const char *channel_name)
{
    if (strcmp(channel_name, "R") == 0)
        return 0;
    if (strcmp(channel_name, "G") == 0)
        return 1;
    if (strcmp(channel_name, "B") == 0)
        return 2;
    return -1;
}

/* ---- EXR writing ------------------------------------------------------- */

/* Points each encoder channel at the first row of the chunk inside our
 * interleaved buffer; the strides make the library step over the other two
 * channels and to the next row. */
static void exr_point_encoder(exr_encode_pipeline_t *encoder, const image *img, int row)
{
    const float *first = img->rgb + (size_t)row * (size_t)img->width * 3;
    for (int c = 0; c < encoder->channel_count; c++) {
        exr_coding_channel_info_t *ch = &encoder->channels[c];
        int offset = rgb_offset(ch->channel_name); /* we only defined R, G, B */
        ch->user_bytes_per_element = (int16_t)sizeof(float);
        ch->user_data_type = (uint16_t)EXR_PIXEL_FLOAT;
        ch->user_pixel_stride = PIXEL_BYTES;
        ch->user_line_stride = PIXEL_BYTES * img->width;
        ch->encode_from_ptr = (const uint8_t *)(first + offset);
    }
}

/* One part, scanlines top to bottom, R G B as 32-bit float, ZIP (lossless,
 * 16 lines per chunk). The part gets no name, so the file is a plain
 * single-part EXR that any reader, old or new, accepts. */
static exr_result_t exr_define_rgb(exr_context_t ctxt, const image *img)
{
    int part = 0;
    exr_result_t rv = exr_add_part(ctxt, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctxt, part, img->width, img->height, EXR_COMPRESSION_ZIP);
    /* Already the default; stated because readers expect chunks in file
     * order. (It is only the storage order: EXR's y axis points down, so
     * row 0 is the top whatever the line order.) */
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_set_lineorder(ctxt, part, EXR_LINEORDER_INCREASING_Y);
    static const char *const names[] = {"R", "G", "B"};
    for (int c = 0; c < 3 && rv == EXR_ERR_SUCCESS; c++)
        rv = exr_add_channel(ctxt, part, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    return rv;
}

/* ZIP's rule for a chunk that does not shrink: store its packed bytes as
 * they are, and a reader, seeing a chunk as long as its pixels, takes them
 * raw. OpenEXR's Core library before 3.2 breaks the rule when the deflated
 * chunk comes out exactly as long as the pixels: it stores the deflated
 * bytes under the raw length, and every reader then decodes them as pixels
 * (garbage up to 1e38 and NaN in one 16-row block of a noisy render). So
 * the library's compressor runs inside this one, which stores the packed
 * bytes itself whenever the result is not shorter, or did not succeed:
 * always a valid ZIP chunk. */
static bool exr_raw_fallback = true; /* image_exr_raw_fallback(); the tests' twin turns it off */
static _Atomic long exr_chunks_raw, exr_chunks_raw_exactly; /* image_exr_raw_chunks() */

static exr_result_t exr_compress_or_store(exr_encode_pipeline_t *encoder)
{
    exr_result_t (*library_compress)(exr_encode_pipeline_t *) = (exr_result_t(*)(exr_encode_pipeline_t *))(
        uintptr_t)encoder->encoding_user_data;
    exr_result_t rv = library_compress(encoder);
    if (rv == EXR_ERR_SUCCESS && encoder->compressed_bytes < encoder->packed_bytes)
        return rv;
    if (encoder->compressed_buffer == NULL || encoder->compressed_alloc_size < encoder->packed_bytes)
        return rv == EXR_ERR_SUCCESS ? EXR_ERR_OUT_OF_MEMORY : rv;
    exr_chunks_raw++;
    exr_chunks_raw_exactly += rv == EXR_ERR_SUCCESS && encoder->compressed_bytes == encoder->packed_bytes &&
                              memcmp(encoder->compressed_buffer, encoder->packed_buffer, encoder->packed_bytes) != 0;
    if (encoder->compressed_buffer != encoder->packed_buffer) {
        if (exr_raw_fallback)
            memcpy(encoder->compressed_buffer, encoder->packed_buffer, encoder->packed_bytes);
        else /* the twin: a raw chunk with other bytes than the pixels' */
            memset(encoder->compressed_buffer, 0xA5, encoder->packed_bytes);
    }
    encoder->compressed_bytes = encoder->packed_bytes;
    return EXR_ERR_SUCCESS;
}

void image_exr_raw_fallback(bool on) { exr_raw_fallback = on; }

void image_exr_raw_chunks(long *raw, long *deflated_to_raw_length)
{
    *raw = exr_chunks_raw;
    *deflated_to_raw_length = exr_chunks_raw_exactly;
}

/* After exr_write_header: encode and write every chunk in order. The
 * pipeline is initialised on the first chunk (which allocates its buffers)
 * and only updated for the rest, so the buffers are reused; the default
 * routines must be chosen after the channel pointers are filled in. */
static exr_result_t exr_write_rgb_chunks(exr_context_t ctxt, const image *img)
{
    int32_t lines_per_chunk = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctxt, 0, &lines_per_chunk);
    if (rv == EXR_ERR_SUCCESS && lines_per_chunk <= 0)
        rv = EXR_ERR_INVALID_ARGUMENT;

    exr_encode_pipeline_t encoder = EXR_ENCODE_PIPELINE_INITIALIZER;
    bool initialized = false;
    for (int y = 0; rv == EXR_ERR_SUCCESS && y < img->height; y += lines_per_chunk) {
        exr_chunk_info_t chunk;
        rv = exr_write_scanline_chunk_info(ctxt, 0, y, &chunk);
        if (rv != EXR_ERR_SUCCESS)
            break;
        if (!initialized) {
            rv = exr_encoding_initialize(ctxt, 0, &chunk, &encoder);
            if (rv != EXR_ERR_SUCCESS)
                break;
            initialized = true;
            exr_point_encoder(&encoder, img, chunk.start_y);
            rv = exr_encoding_choose_default_routines(ctxt, 0, &encoder);
        } else {
            rv = exr_encoding_update(ctxt, 0, &chunk, &encoder);
            exr_point_encoder(&encoder, img, chunk.start_y);
        }
        if (encoder.compress_fn != NULL && encoder.compress_fn != exr_compress_or_store) { /* NULL: no compression */
            encoder.encoding_user_data = (void *)(uintptr_t)encoder.compress_fn;
            encoder.compress_fn = exr_compress_or_store;
        }
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_encoding_run(ctxt, 0, &encoder);
    }
    if (initialized)
        exr_encoding_destroy(ctxt, &encoder);
    return rv;
}

bool image_encode_exr(const image *img, int fd, const char *path, char *err, size_t err_size)
{
    if (!image_is_writable(img)) {
        set_error(err, err_size, "cannot write '%s': the image is empty or too wide", path);
        return false;
    }
    exr_stream stream = {.fd = fd, .message = ""};
    exr_context_initializer_t init = exr_initializer(&stream);
    exr_context_t ctxt = NULL;
    /* With a custom write_fn the name is only used in messages and the mode
     * is ignored: the descriptor is the caller's, not the library's. */
    exr_result_t rv = exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_define_rgb(ctxt, img);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctxt);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_rgb_chunks(ctxt, img);
    if (ctxt != NULL) {
        /* exr_finish writes the chunk offset table, so it is part of the
         * write and its result counts; it also frees the context. */
        exr_result_t finished = exr_finish(&ctxt);
        if (rv == EXR_ERR_SUCCESS)
            rv = finished;
    }
    exr_current_stream = NULL;
    if (rv != EXR_ERR_SUCCESS) {
        set_error(err, err_size, "cannot write '%s': %s", path, exr_stream_reason(&stream, rv));
        return false;
    }
    return true;
}

/* ---- EXR reading ------------------------------------------------------- */

/* Points the R, G, B decoder channels at the chunk's first row in our
 * buffer (as float, whatever the file stores); other channels get NULL,
 * which tells the library to skip them. */
static void exr_point_decoder(exr_decode_pipeline_t *decoder, image *img, int row)
{
    float *first = img->rgb + (size_t)row * (size_t)img->width * 3;
    for (int c = 0; c < decoder->channel_count; c++) {
        exr_coding_channel_info_t *ch = &decoder->channels[c];
        int offset = rgb_offset(ch->channel_name);
        if (offset < 0) {
            ch->decode_to_ptr = NULL;
            continue;
        }
        ch->user_bytes_per_element = (int16_t)sizeof(float);
        ch->user_data_type = (uint16_t)EXR_PIXEL_FLOAT;
        ch->user_pixel_stride = PIXEL_BYTES;
        ch->user_line_stride = PIXEL_BYTES * img->width;
        ch->decode_to_ptr = (uint8_t *)(first + offset);
    }
}

/* Checks that part 0 is something we can read: scanline, with full
 * resolution R, G and B channels in half or float. Our own reasons for
 * refusing go into why (with EXR_ERR_INVALID_ATTR); the library's go to the
 * stream. */
static exr_result_t exr_check_rgb(exr_context_t ctxt, char *why, size_t why_size)
{
    exr_storage_t storage;
    exr_result_t rv = exr_get_storage(ctxt, 0, &storage);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    if (storage != EXR_STORAGE_SCANLINE) {
        snprintf(why, why_size, "only scanline images can be read (this one is tiled or deep)");
        return EXR_ERR_INVALID_ATTR;
    }
    const exr_attr_chlist_t *channels = NULL;
    rv = exr_get_channels(ctxt, 0, &channels);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    static const char *const names[] = {"R", "G", "B"};
    for (int c = 0; c < 3; c++) {
        const exr_attr_chlist_entry_t *found = NULL;
        for (int i = 0; i < channels->num_channels; i++)
            if (strcmp(channels->entries[i].name.str, names[c]) == 0)
                found = &channels->entries[i];
        if (found == NULL)
            snprintf(why, why_size, "no '%s' channel (R, G and B are needed)", names[c]);
        else if (found->pixel_type != EXR_PIXEL_HALF && found->pixel_type != EXR_PIXEL_FLOAT)
            snprintf(why, why_size, "channel '%s' is not half or float", names[c]);
        else if (found->x_sampling != 1 || found->y_sampling != 1)
            snprintf(why, why_size, "channel '%s' is subsampled", names[c]);
        if (why[0] != '\0')
            return EXR_ERR_INVALID_ATTR;
    }
    return EXR_ERR_SUCCESS;
}

/* Decodes every chunk of part 0 into img, which must already have the data
 * window's size. Same pipeline life cycle as writing: initialise on the
 * first chunk, fill in the channels, choose routines; update afterwards. */
static exr_result_t exr_read_rgb_chunks(exr_context_t ctxt, const exr_attr_box2i_t *window, image *img)
{
    int32_t lines_per_chunk = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctxt, 0, &lines_per_chunk);
    if (rv == EXR_ERR_SUCCESS && lines_per_chunk <= 0)
        rv = EXR_ERR_INVALID_ARGUMENT;

    exr_decode_pipeline_t decoder = EXR_DECODE_PIPELINE_INITIALIZER;
    bool initialized = false;
    /* y is in file coordinates (the data window may not start at 0); rows
     * in img count from the window's top. int64 so the step can't overflow
     * at the bottom of a window near INT32_MAX. */
    for (int64_t y = window->min.y; rv == EXR_ERR_SUCCESS && y <= window->max.y; y += lines_per_chunk) {
        exr_chunk_info_t chunk;
        rv = exr_read_scanline_chunk_info(ctxt, 0, (int)y, &chunk);
        if (rv != EXR_ERR_SUCCESS)
            break;
        int row = chunk.start_y - window->min.y;
        if (!initialized) {
            rv = exr_decoding_initialize(ctxt, 0, &chunk, &decoder);
            if (rv != EXR_ERR_SUCCESS)
                break;
            initialized = true;
            exr_point_decoder(&decoder, img, row);
            rv = exr_decoding_choose_default_routines(ctxt, 0, &decoder);
        } else {
            rv = exr_decoding_update(ctxt, 0, &chunk, &decoder);
            exr_point_decoder(&decoder, img, row);
        }
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_decoding_run(ctxt, 0, &decoder);
    }
    if (initialized)
        exr_decoding_destroy(ctxt, &decoder);
    return rv;
}

/* Reads part 0 of an already opened file; the data window becomes the
 * image (the display window is ignored). why gets our own reasons; the
 * library's go to the stream. */
static exr_result_t exr_read_rgb(exr_context_t ctxt, image *img, char *why, size_t why_size)
{
    exr_result_t rv = exr_check_rgb(ctxt, why, why_size);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    exr_attr_box2i_t window;
    rv = exr_get_data_window(ctxt, 0, &window);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    int64_t width = (int64_t)window.max.x - window.min.x + 1;
    int64_t height = (int64_t)window.max.y - window.min.y + 1;
    if (width <= 0 || height <= 0 || width > INT32_MAX / PIXEL_BYTES || height > INT32_MAX) {
        snprintf(why, why_size, "unsupported data window %lld x %lld", (long long)width, (long long)height);
        return EXR_ERR_INVALID_ATTR;
    }
    *img = image_make((int)width, (int)height);
    if (img->rgb == NULL) {
        snprintf(why, why_size, "no memory for %lld x %lld pixels", (long long)width, (long long)height);
        return EXR_ERR_OUT_OF_MEMORY;
    }
    return exr_read_rgb_chunks(ctxt, &window, img);
}

bool image_read_exr(image *out, const char *path, char *err, size_t err_size)
{
    /* On failure *out is an empty image, so image_free on it is harmless. */
    *out = (image){0, 0, NULL};
    exr_stream stream = {.fd = open(path, O_RDONLY | O_CLOEXEC), .message = ""};
    if (stream.fd < 0) {
        set_error(err, err_size, "cannot read '%s': %s", path, strerror(errno));
        return false;
    }
    exr_context_initializer_t init = exr_initializer(&stream);
    exr_context_t ctxt = NULL;
    image img = {0, 0, NULL};
    char why[256] = "";
    exr_result_t rv = exr_start_read(&ctxt, path, &init);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_read_rgb(ctxt, &img, why, sizeof why);
    if (ctxt != NULL)
        exr_finish(&ctxt);
    exr_current_stream = NULL;
    close(stream.fd);
    if (rv != EXR_ERR_SUCCESS) {
        set_error(err, err_size, "cannot read '%s': %s", path,
                  why[0] != '\0' ? why : exr_stream_reason(&stream, rv));
        image_free(&img);
        return false;
    }
    *out = img;
    return true;
}

/* ---- PNG preview ------------------------------------------------------- */

float image_srgb_encode(float linear)
{
    /* IEC 61966-2-1: a linear toe below 0.0031308, a 1/2.4 power above;
     * the constants make the two pieces meet (to about 1e-7). */
    if (linear <= 0.0031308f)
        return 12.92f * linear;
    return 1.055f * powf(linear, 1.0f / 2.4f) - 0.055f;
}

/* One preview channel. The test is written !(v > 0) so NaN lands on 0
 * too: converting NaN (or anything out of range) to an integer is
 * undefined behaviour in C. After the clamp the encoded value is in
 * [0, 1], so + 0.5 and truncation round to nearest safely. */
static unsigned char preview_byte(float linear, float scale)
{
    float v = linear * scale;
    if (!(v > 0.0f))
        return 0;
    if (v >= 1.0f)
        return 255;
    return (unsigned char)(image_srgb_encode(v) * 255.0f + 0.5f);
}

/* stb calls this with the encoded bytes. It can't report failure, so the
 * first errno is kept and later calls do nothing. */
typedef struct {
    int fd;
    int error;
} png_sink;

static void png_sink_write(void *context, void *data, int size)
{
    png_sink *sink = context;
    const unsigned char *bytes = data;
    size_t left = size > 0 ? (size_t)size : 0;
    while (sink->error == 0 && left > 0) {
        ssize_t n = write(sink->fd, bytes, left);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            sink->error = n < 0 ? errno : EIO;
            break;
        }
        bytes += n;
        left -= (size_t)n;
    }
}

bool image_encode_png(const image *img, int fd, const char *path, float exposure_stops, char *err, size_t err_size)
{
    if (!image_is_writable(img)) {
        set_error(err, err_size, "cannot write '%s': the image is empty or too wide", path);
        return false;
    }
    size_t count = (size_t)img->width * (size_t)img->height * 3;
    unsigned char *bytes = malloc(count);
    if (bytes == NULL) {
        set_error(err, err_size, "cannot write '%s': %s", path, strerror(ENOMEM));
        return false;
    }
    float scale = exp2f(exposure_stops);
    for (size_t i = 0; i < count; i++)
        bytes[i] = preview_byte(img->rgb[i], scale);

    /* stbi_write_png_to_func rather than stbi_write_png(filename): it writes
     * onto the caller's descriptor, and we see write errors (stbi_write_png
     * ignores a failing fwrite or fclose, e.g. on a full disk). */
    png_sink sink = {fd, 0};
    int encoded = stbi_write_png_to_func(png_sink_write, &sink, img->width, img->height, 3, bytes, img->width * 3);
    free(bytes);
    if (!encoded || sink.error != 0) {
        set_error(err, err_size, "cannot write '%s': %s", path,
                  sink.error != 0 ? strerror(sink.error) : "PNG encoding failed");
        return false;
    }
    return true;
}

/* ---- error metrics ----------------------------------------------------- */

/* Both metrics return NaN for images of different sizes (or empty ones):
 * there is no meaningful number, and NaN can't be mistaken for a good one. */
static bool same_size(const image *a, const image *b)
{
    return a->rgb != NULL && b->rgb != NULL && a->width == b->width && a->height == b->height &&
           a->width > 0 && a->height > 0;
}

double image_mse(const image *a, const image *reference)
{
    if (!same_size(a, reference))
        return NAN;
    size_t count = (size_t)a->width * (size_t)a->height * 3;
    double sum = 0.0;
    for (size_t i = 0; i < count; i++) {
        double d = (double)a->rgb[i] - (double)reference->rgb[i];
        sum += d * d;
    }
    return sum / (double)count;
}

double image_relmse(const image *a, const image *reference)
{
    if (!same_size(a, reference))
        return NAN;
    size_t count = (size_t)a->width * (size_t)a->height * 3;
    double sum = 0.0;
    for (size_t i = 0; i < count; i++) {
        double r = (double)reference->rgb[i];
        double d = (double)a->rgb[i] - r;
        sum += d * d / (r * r + IMAGE_RELMSE_EPSILON);
    }
    return sum / (double)count;
}
